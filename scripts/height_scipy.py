"""SciPy's DCT Poisson solve of the same float32 normal-integration problem as skinkit's Neumann
integrator (scripts/bench-height-vs-scipy.sh): one JSON line with the median time of RUNS."""
import json
import os
import sys
import time

import numpy as np
import scipy.fft


def normals(side):
    y, x = np.mgrid[0:side, 0:side].astype(np.float32)
    u, v = x * np.float32(0.013), y * np.float32(0.021)
    n = np.stack([0.3 * np.sin(u) * np.cos(v), 0.2 * np.cos(u + v), np.ones_like(u)], axis=-1)
    return (n / np.linalg.norm(n, axis=-1, keepdims=True)).astype(np.float32)


def integrate(n):
    p = -n[..., 0] / n[..., 2]
    q = n[..., 1] / n[..., 2]
    h, w = p.shape
    ex = 0.5 * (p[:, :-1] + p[:, 1:])
    ey = 0.5 * (q[:-1, :] + q[1:, :])
    b = np.zeros((h, w), np.float32)
    b[:, 1:] += ex
    b[:, :-1] -= ex
    b[1:, :] += ey
    b[:-1, :] -= ey
    workers = os.cpu_count()
    f = scipy.fft.dctn(b, type=2, workers=workers)
    mx = 2 - 2 * np.cos(np.pi * np.arange(w, dtype=np.float32) / w)
    my = 2 - 2 * np.cos(np.pi * np.arange(h, dtype=np.float32) / h)
    mu = my[:, None] + mx[None, :]
    mu[0, 0] = 1
    f /= mu
    f[0, 0] = 0
    return scipy.fft.idctn(f, type=2, workers=workers)


side = int(sys.argv[1])
runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3
n = normals(side)
times = []
for _ in range(runs):
    t = time.perf_counter()
    integrate(n)
    times.append(time.perf_counter() - t)
times.sort()
print(json.dumps({"side": side, "median_s": times[len(times) // 2]}))
