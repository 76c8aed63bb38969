#!/usr/bin/env bash
# `skinkit capture` against a numpy + OpenCV one-shot script (scripts/capture_numpy.py) on the
# same 8 photos of 4096x4096 16-bit grey (rendered once by `skinkit samples`), in the same run,
# alternating them RUNS times: end-to-end seconds (wall clock), CPU seconds (user + system) and
# peak memory (maximum resident set from /usr/bin/time -v), then the medians and their ratios.
# The script solves by least squares over all lights, so `skinkit capture --solver ls` is its
# like-for-like peer; the default robust solve (more work per pixel) is measured beside it.
#   bash scripts/bench-capture-vs-numpy.sh [WORK_DIR] [RUNS]    (SKINKIT_BIN=path: use that build)
# Needs python3 with numpy and OpenCV's EXR codec; installs them with pip when missing (OpenCV
# below 5: the 5.0 wheels have no EXR writer; Debian's python3-numpy python3-opencv also do).
# After the runs, the cost of camera RAW decoding beside them: one 8192x8192-sensor DNG decoded
# at half size (4096x4096, the photos' size) and full size (the example raw_decode_timing).
# Not for CI. The machine is shared: read the load printed before and after.
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-/tmp/skinkit-bench}
runs=${2:-5}
: ${SKINKIT_BIN:=}; [ -n "$SKINKIT_BIN" ] || cargo build --release -q -p skinkit-cli
bin=${SKINKIT_BIN:-target/release/skinkit}
python3 -c "import numpy, cv2" 2>/dev/null || pip install -q numpy "opencv-python-headless<5"
if [ ! -f "$work/photos/cheek/08.png" ]; then
  "$bin" samples --quiet --size 4096 --out "$work/photos"
fi
session="$work/photos/cheek"
log="$work/runs.tsv"
: > "$log"
measure() { # name, command...: appends "name seconds peak_kib cpu_seconds" to the log
  local name=$1
  shift
  /usr/bin/time -v "$@" 2> "$work/time.txt" > /dev/null
  local secs kib
  secs=$(grep "Elapsed (wall clock)" "$work/time.txt" | awk -F': ' '{print $2}' | awk -F: '{ if (NF == 3) print $1 * 3600 + $2 * 60 + $3; else print $1 * 60 + $2 }')
  kib=$(grep "Maximum resident set size" "$work/time.txt" | awk -F': ' '{print $2}')
  cpu=$(grep -E "(User|System) time" "$work/time.txt" | awk -F': ' '{s += $2} END {print s}')
  printf '%s\t%s\t%s\t%s\n' "$name" "$secs" "$kib" "$cpu" | tee -a "$log"
}
echo "load before: $(uptime)"
for i in $(seq "$runs"); do
  measure skinkit-ls "$bin" capture --quiet --solver ls --rig "$session/rig.toml" --photos-from "$session" --out "$work/out-skinkit-ls"
  measure skinkit-robust "$bin" capture --quiet --rig "$session/rig.toml" --photos-from "$session" --out "$work/out-skinkit"
  measure numpy python3 scripts/capture_numpy.py "$session/rig.toml" "$session" "$work/out-numpy"
done
echo "load after: $(uptime)"
python3 - "$log" <<'PY'
import statistics, sys
rows = [l.split("\t") for l in open(sys.argv[1]).read().splitlines()]
med = {}
for name in ("skinkit-ls", "skinkit-robust", "numpy"):
    secs = [float(r[1]) for r in rows if r[0] == name]
    mib = [int(r[2]) / 1024 for r in rows if r[0] == name]
    cpu = [float(r[3]) for r in rows if r[0] == name]
    med[name] = (statistics.median(secs), statistics.median(mib), statistics.median(cpu))
    print(f"{name}: median {med[name][0]:.2f} s (runs {', '.join(f'{s:.2f}' for s in secs)}), "
          f"median CPU {med[name][2]:.2f} s, median peak {med[name][1]:.0f} MiB")
for name in ("skinkit-ls", "skinkit-robust"):
    print(f"{name} is {med['numpy'][0] / med[name][0]:.2f}x faster end to end than the script "
          f"({med['numpy'][2] / med[name][2]:.2f}x less CPU) and uses {med[name][1] / med['numpy'][1]:.2f} "
          f"of its peak memory")
PY
echo "camera RAW decoding, beside the runs above (8 such photos would add 8x the half-size time):"
cargo run --release -q -p skinkit-capture --example raw_decode_timing 8192 3
