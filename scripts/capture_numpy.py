#!/usr/bin/env python3
"""A one-shot numpy + OpenCV photometric-stereo capture, the peer of `skinkit capture --solver ls`
in scripts/bench-capture-vs-numpy.sh: the same inputs, stages and outputs, written the way a
careful lab script would be: whole-image arrays, one batched pseudo-inverse solve over all pixels
(BLAS), OpenCV for the codecs and the box filter, no Python loop over pixels.

    python3 scripts/capture_numpy.py RIG.toml PHOTO_DIR OUT_DIR [--block 50]

Stages, as skinkit's least-squares capture (Haro et al. 2001, section 3):
  decode   cv2.imread(IMREAD_UNCHANGED) of the photos (sorted *.png/*.tif but mask/ambient/truth)
           into one k x H x W array;
  solve    g = P r for every pixel at once, P the rig's 3 x k pseudo-inverse with the 1/65535
           scale and each light's intensity folded in (one float32 matrix product); albedo |g|,
           normal g/|g|, confidence 1 / (1 + (rho / 0.1)^2) from the relative residual rho, whose
           square comes from the normal equations (|r|^2 - g . L^T r) rather than a k x N refit;
  detrend  the mean normal of the block centred on each pixel (cv2.blur) rotated to +Z, the same
           rotation applied to the pixel (Rodrigues);
  stats    tilt of the normals from +Z: mean, rms, median, p95, max;
  write    normal.exr (float, uncompressed), normal.png (16-bit), albedo.png (16-bit),
           confidence.png (8-bit), report.json with the stage timings.

Needs numpy and OpenCV with its EXR codec: `pip install numpy "opencv-python-headless<5"` (the
5.0 wheels have no EXR writer; Debian's python3-opencv works too). The bench script installs them.
"""

import json
import os
import sys
import time
import tomllib

os.environ.setdefault("OPENCV_IO_ENABLE_OPENEXR", "1")
import cv2  # noqa: E402
import numpy as np  # noqa: E402

MIN_ALBEDO = 1e-6
RESIDUAL_SCALE = 0.1


def load_rig(path):
    """Unit light directions (k x 3, float64) and each light's grey intensity (k)."""
    with open(path, "rb") as f:
        rig = tomllib.load(f)
    dirs = np.array([light["direction"] for light in rig["light"]], dtype=np.float64)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    intensity = np.array([float(np.mean(light.get("intensity", 1.0))) for light in rig["light"]])
    return dirs, intensity


def photo_paths(folder):
    names = sorted(
        n for n in os.listdir(folder)
        if n.lower().endswith((".png", ".tif", ".tiff"))
        and os.path.splitext(n)[0].lower() not in ("mask", "ambient", "truth")
    )
    return [os.path.join(folder, n) for n in names]


def decode(paths):
    """The photos as one k x H x W uint16 array (grey 16-bit photos, as the benchmark renders)."""
    first = cv2.imread(paths[0], cv2.IMREAD_UNCHANGED)
    stack = np.empty((len(paths),) + first.shape, first.dtype)
    stack[0] = first
    for i, p in enumerate(paths[1:], 1):
        stack[i] = cv2.imread(p, cv2.IMREAD_UNCHANGED)
    return stack


def solve(raw, dirs, intensity):
    """raw: k x N uint16. Returns normals (N x 3), albedo (N), confidence (N), all float32."""
    scale = 1.0 / (65535.0 * intensity)  # stored value -> intensity-divided reading
    pinv = (np.linalg.pinv(dirs) * scale[None, :]).astype(np.float32)  # 3 x k
    lt = (dirs.T * scale[None, :]).astype(np.float32)  # L^T with the same scale
    samples = raw.astype(np.float32)  # k x N
    g = pinv @ samples  # 3 x N
    b = lt @ samples  # L^T r, 3 x N
    rr = np.einsum("k,kn,kn->n", (scale**2).astype(np.float32), samples, samples)
    del samples
    res = np.maximum(rr - np.einsum("jn,jn->n", g, b), 0.0)  # |r - L g|^2 at the optimum
    albedo = np.sqrt(np.einsum("jn,jn->n", g, g))
    valid = (albedo > MIN_ALBEDO) & np.isfinite(albedo)
    normals = np.where(valid, g / np.where(valid, albedo, 1.0), 0.0).T.astype(np.float32)
    rho2 = np.divide(res, rr, out=np.zeros_like(rr), where=rr > 0)
    confidence = np.where(valid, 1.0 / (1.0 + rho2 / RESIDUAL_SCALE**2), 0.0).astype(np.float32)
    return normals, np.where(valid, albedo, 0.0).astype(np.float32), confidence, valid


def detrend(normals, block):
    """normals: H x W x 3 unit (or zero) vectors, rotated so block means point at +Z."""
    if block == 0:
        return normals
    side = 2 * (block // 2) + 1
    mean = cv2.blur(normals, (side, side), borderType=cv2.BORDER_REFLECT)
    mean /= np.maximum(np.linalg.norm(mean, axis=2, keepdims=True), 1e-12)
    # Rodrigues with v = m x z, cos = m . z: n' = n c + v x n + v (v . n) / (1 + c).
    v = np.stack([mean[..., 1], -mean[..., 0], np.zeros_like(mean[..., 0])], axis=2)
    c = mean[..., 2:3]
    out = normals * c + np.cross(v, normals) + v * (np.sum(v * normals, axis=2, keepdims=True) / np.maximum(1.0 + c, 1e-6))
    valid = np.any(normals != 0, axis=2, keepdims=True)
    return np.where(valid, out, 0.0).astype(np.float32)


def tilt_stats(normals):
    flat = normals.reshape(-1, 3)
    ok = np.any(flat != 0, axis=1)
    tilt = np.degrees(np.arctan2(np.linalg.norm(flat[ok, :2], axis=1), flat[ok, 2]))
    return {
        "count": int(tilt.size), "mean": float(tilt.mean()), "rms": float(np.sqrt(np.mean(tilt**2))),
        "median": float(np.median(tilt)), "p95": float(np.percentile(tilt, 95)), "max": float(tilt.max()),
    }


def write(out, normals, albedo, confidence):
    os.makedirs(out, exist_ok=True)
    bgr = np.ascontiguousarray(normals[..., ::-1])
    cv2.imwrite(os.path.join(out, "normal.exr"), bgr,
                [cv2.IMWRITE_EXR_TYPE, cv2.IMWRITE_EXR_TYPE_FLOAT, cv2.IMWRITE_EXR_COMPRESSION, cv2.IMWRITE_EXR_COMPRESSION_NO])
    valid = np.any(bgr != 0, axis=2, keepdims=True)
    png16 = np.where(valid, np.round((bgr + 1.0) * 0.5 * 65535.0), 0).astype(np.uint16)
    fast = [cv2.IMWRITE_PNG_COMPRESSION, 1]
    cv2.imwrite(os.path.join(out, "normal.png"), png16, fast)
    cv2.imwrite(os.path.join(out, "albedo.png"), np.round(np.clip(albedo, 0, 1) * 65535.0).astype(np.uint16), fast)
    cv2.imwrite(os.path.join(out, "confidence.png"), np.round(np.clip(confidence, 0, 1) * 255.0).astype(np.uint8), fast)


def parse_args(argv):
    block = 50
    if "--block" in argv:
        i = argv.index("--block")
        block = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if len(argv) != 3:
        sys.exit(__doc__)
    return (*argv, block)


def main():
    rig_path, folder, out, block = parse_args(sys.argv[1:])
    t0 = time.perf_counter()
    timings = {}
    dirs, intensity = load_rig(rig_path)
    paths = photo_paths(folder)
    if len(paths) != len(dirs):
        sys.exit(f"rig has {len(dirs)} lights but {len(paths)} photos were found")

    t = time.perf_counter()
    stack = decode(paths)
    k, h, w = stack.shape
    timings["decode"] = time.perf_counter() - t

    t = time.perf_counter()
    normals, albedo, confidence, valid = solve(stack.reshape(k, -1), dirs, intensity)
    del stack
    timings["solve"] = time.perf_counter() - t

    t = time.perf_counter()
    normals = detrend(normals.reshape(h, w, 3), block)
    timings["detrend"] = time.perf_counter() - t

    t = time.perf_counter()
    stats = tilt_stats(normals)
    timings["stats"] = time.perf_counter() - t

    t = time.perf_counter()
    write(out, normals, albedo.reshape(h, w), confidence.reshape(h, w))
    timings["write"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    report = {"width": w, "height": h, "light_count": k, "invalid_pixels": int((~valid).sum()),
              "tilt_degrees": stats, "timings_s": timings}
    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
