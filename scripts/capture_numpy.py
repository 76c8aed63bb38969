#!/usr/bin/env python3
"""A one-shot numpy + OpenCV photometric-stereo capture, the peer of `skinkit capture` in
scripts/bench-capture-vs-numpy.sh: the same inputs, stages and outputs, written the way a lab
script would be (whole-image arrays, BLAS for the products, OpenCV for the codecs and the box
filter).

    python3 scripts/capture_numpy.py RIG.toml PHOTO_DIR OUT_DIR [--block 50]

Stages, as skinkit's: decode the photos (sorted *.png but mask/ambient/truth), per pixel drop
readings under max(0.005, 0.05 x the pixel's brightest) or at or above 99.5 % of full scale and
solve the rest by least squares (all-lights pixels through the rig's pseudo-inverse, the others
through batched 3x3 normal equations), albedo |g|, normal g/|g|, confidence from the lights used
and the residual, the detrend (the mean normal of the block centred on each pixel rotated to +Z,
the same rotation applied to the pixel), tilt statistics, and the outputs normal.exr (float,
uncompressed), normal.png (16-bit), albedo.png (16-bit), confidence.png (8-bit), report.json.
Needs numpy and opencv-python-headless.
"""

import json
import os
import sys
import time
import tomllib

os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
import cv2  # noqa: E402
import numpy as np  # noqa: E402

SHADOW_ABS, SHADOW_REL, SATURATION, MIN_ALBEDO = 0.005, 0.05, 0.995, 1e-6


def load_rig(path):
    with open(path, "rb") as f:
        rig = tomllib.load(f)
    dirs = np.array([l["direction"] for l in rig["light"]], dtype=np.float64)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    intensity = np.array([float(np.mean(l.get("intensity", 1.0))) for l in rig["light"]])
    return dirs, intensity


def photo_paths(folder):
    names = sorted(
        n for n in os.listdir(folder)
        if n.lower().endswith((".png", ".tif", ".tiff")) and os.path.splitext(n)[0].lower() not in ("mask", "ambient", "truth")
    )
    return [os.path.join(folder, n) for n in names]


def solve(raw, dirs, intensity):
    """raw: k x N uint16. Returns g (N x 3, float32), lights used (N), residual factor (N)."""
    k = raw.shape[0]
    full = 65535.0
    r = raw.astype(np.float32) * (1.0 / full) / intensity[:, None].astype(np.float32)
    pinv = np.linalg.pinv(dirs).astype(np.float32)  # 3 x k
    g = (pinv @ r).T.copy()  # N x 3
    floor = np.maximum(SHADOW_ABS, SHADOW_REL * r.max(axis=0))
    drop = (r < floor) | (raw >= SATURATION * full)
    used = k - drop.sum(axis=0)
    some = np.nonzero(used < k)[0]
    if some.size:
        w = (~drop[:, some]).astype(np.float32)  # k x m
        l32 = dirs.astype(np.float32)
        outer = (l32[:, :, None] * l32[:, None, :]).reshape(k, 9)
        a = (w.T @ outer).reshape(-1, 3, 3)  # per pixel sum of the used lights' L L^T (BLAS)
        b = (w * r[:, some]).T @ l32
        ok = (used[some] >= 3) & (np.abs(np.linalg.det(a)) > 1e-6)
        sol = np.zeros((some.size, 3), np.float32)
        sol[ok] = np.linalg.solve(a[ok], b[ok][:, :, None])[:, :, 0]
        g[some] = sol
    fitted = (dirs.astype(np.float32) @ g.T)  # k x N
    rr = np.where(drop, 0.0, r * r).sum(axis=0)
    res = np.where(drop, 0.0, (r - fitted) ** 2).sum(axis=0)
    rho2 = np.divide(res, rr, out=np.zeros_like(rr), where=rr > 0)
    residual_factor = 1.0 / (1.0 + rho2 / 0.01)
    return g, used, residual_factor


def detrend(normals, block):
    """normals: H x W x 3 unit (or zero) vectors, rotated in place so block means point at +Z."""
    if block == 0:
        return normals
    mean = cv2.blur(normals, (block | 1, block | 1), borderType=cv2.BORDER_REFLECT)
    mean /= np.maximum(np.linalg.norm(mean, axis=2, keepdims=True), 1e-12)
    # Rodrigues: the rotation taking m to z applied to n.
    v = np.stack([mean[..., 1], -mean[..., 0], np.zeros_like(mean[..., 0])], axis=2)  # m x z
    c = mean[..., 2:3]
    cross = np.cross(v, normals)
    vdotn = np.sum(v * normals, axis=2, keepdims=True)
    out = normals * c + cross + v * vdotn / np.maximum(1.0 + c, 1e-6)
    valid = np.any(normals != 0, axis=2, keepdims=True)
    return np.where(valid, out, 0.0).astype(np.float32)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    block = int(sys.argv[sys.argv.index("--block") + 1]) if "--block" in sys.argv else 50
    if "--block" in sys.argv:
        args.remove(str(block))
    rig_path, folder, out = args
    t0 = time.perf_counter()
    timings = {}
    dirs, intensity = load_rig(rig_path)
    paths = photo_paths(folder)
    if len(paths) != len(dirs):
        sys.exit(f"rig has {len(dirs)} lights but {len(paths)} photos were found")

    t = time.perf_counter()
    photos = [cv2.imread(p, cv2.IMREAD_UNCHANGED) for p in paths]
    h, w = photos[0].shape[:2]
    raw = np.stack(photos).reshape(len(paths), -1)
    del photos
    timings["decode"] = time.perf_counter() - t

    t = time.perf_counter()
    g, used, residual_factor = solve(raw, dirs, intensity)
    del raw
    albedo = np.linalg.norm(g, axis=1)
    valid = (albedo > MIN_ALBEDO) & np.isfinite(albedo)
    normals = np.where(valid[:, None], g / np.where(valid, albedo, 1.0)[:, None], 0.0).astype(np.float32)
    albedo = np.where(valid, albedo, 0.0).astype(np.float32)
    confidence = np.where(valid, used / len(dirs) * residual_factor, 0.0).astype(np.float32)
    del g
    timings["solve"] = time.perf_counter() - t

    t = time.perf_counter()
    normals = detrend(normals.reshape(h, w, 3), block)
    timings["detrend"] = time.perf_counter() - t

    t = time.perf_counter()
    flat = normals.reshape(-1, 3)
    ok = np.any(flat != 0, axis=1)
    tilt = np.degrees(np.arctan2(np.linalg.norm(flat[ok, :2], axis=1), flat[ok, 2]))
    stats = {
        "count": int(tilt.size), "mean": float(tilt.mean()), "rms": float(np.sqrt(np.mean(tilt**2))),
        "median": float(np.median(tilt)), "p95": float(np.percentile(tilt, 95)), "max": float(tilt.max()),
    }
    timings["stats"] = time.perf_counter() - t

    t = time.perf_counter()
    os.makedirs(out, exist_ok=True)
    bgr = normals[..., ::-1]
    cv2.imwrite(os.path.join(out, "normal.exr"), np.ascontiguousarray(bgr),
                [cv2.IMWRITE_EXR_TYPE, cv2.IMWRITE_EXR_TYPE_FLOAT, cv2.IMWRITE_EXR_COMPRESSION, cv2.IMWRITE_EXR_COMPRESSION_NO])
    png16 = np.where(np.any(bgr != 0, axis=2, keepdims=True), np.round((bgr + 1.0) * 0.5 * 65535.0), 0).astype(np.uint16)
    cv2.imwrite(os.path.join(out, "normal.png"), png16, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    cv2.imwrite(os.path.join(out, "albedo.png"), np.round(np.clip(albedo, 0, 1) * 65535.0).astype(np.uint16).reshape(h, w),
                [cv2.IMWRITE_PNG_COMPRESSION, 1])
    cv2.imwrite(os.path.join(out, "confidence.png"), np.round(np.clip(confidence, 0, 1) * 255.0).astype(np.uint8).reshape(h, w),
                [cv2.IMWRITE_PNG_COMPRESSION, 1])
    timings["write"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    report = {"width": w, "height": h, "light_count": len(dirs), "invalid_pixels": int((~valid).sum()),
              "tilt_degrees": stats, "timings_s": timings}
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
