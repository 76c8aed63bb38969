#!/usr/bin/env bash
# `skinkit capture` against a numpy + OpenCV one-shot script (scripts/capture_numpy.py) on the
# same 8 photos of 4096x4096 16-bit grey (rendered once by `skinkit samples`), in the same run,
# alternating the two RUNS times: end-to-end seconds (wall clock) and peak memory (maximum
# resident set from /usr/bin/time -v), then the medians and their ratios.
#   bash scripts/bench-capture-vs-numpy.sh [WORK_DIR] [RUNS]    (SKINKIT_BIN=path: use that build)
# Needs python3 with numpy and OpenCV; installs them with pip when missing (OpenCV below 5: the
# 5.0 wheels have no EXR writer). Not for CI.
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
measure() { # name, command...: appends "name seconds peak_kib" to the log
  local name=$1
  shift
  /usr/bin/time -v "$@" 2> "$work/time.txt" > /dev/null
  local secs kib
  secs=$(grep "Elapsed (wall clock)" "$work/time.txt" | awk -F': ' '{print $2}' | awk -F: '{ if (NF == 3) print $1 * 3600 + $2 * 60 + $3; else print $1 * 60 + $2 }')
  kib=$(grep "Maximum resident set size" "$work/time.txt" | awk -F': ' '{print $2}')
  printf '%s\t%s\t%s\n' "$name" "$secs" "$kib" | tee -a "$log"
}
echo "load before: $(uptime)"
for i in $(seq "$runs"); do
  measure skinkit "$bin" capture --quiet --rig "$session/rig.toml" --photos-from "$session" --out "$work/out-skinkit"
  measure numpy python3 scripts/capture_numpy.py "$session/rig.toml" "$session" "$work/out-numpy"
done
echo "load after: $(uptime)"
python3 - "$log" <<'PY'
import statistics, sys
rows = [l.split("\t") for l in open(sys.argv[1]).read().splitlines()]
med = {}
for name in ("skinkit", "numpy"):
    secs = [float(r[1]) for r in rows if r[0] == name]
    mib = [int(r[2]) / 1024 for r in rows if r[0] == name]
    med[name] = (statistics.median(secs), statistics.median(mib))
    print(f"{name}: median {med[name][0]:.2f} s (runs {', '.join(f'{s:.2f}' for s in secs)}), "
          f"median peak {med[name][1]:.0f} MiB")
print(f"skinkit is {med['numpy'][0] / med['skinkit'][0]:.2f}x faster end to end and uses "
      f"{med['skinkit'][1] / med['numpy'][1]:.2f} of the script's peak memory")
PY
