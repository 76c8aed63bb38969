#!/usr/bin/env bash
# End-to-end capture benchmark: 8 photos of 4096x4096, 16-bit grey, under the turntable rig.
# Renders the photos once (about a minute), then runs `skinkit capture` RUNS times and prints the
# per-stage timings from report.json and the peak memory measured by the kernel (VmHWM).
#   bash scripts/bench-capture.sh [WORK_DIR] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-/tmp/skinkit-bench}
runs=${2:-5}
cargo build --release -q -p skinkit-cli
bin=target/release/skinkit
if [ ! -f "$work/photos/cheek/08.png" ]; then
  "$bin" samples --quiet --size 4096 --out "$work/photos"
fi
for i in $(seq "$runs"); do
  "$bin" capture --quiet --rig "$work/photos/cheek/rig.toml" --photos-from "$work/photos/cheek" --out "$work/out"
  python3 - "$work/out/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
t = r["timings_s"]
print("total %.3f s  decode %.3f  solve %.3f  detrend %.3f  stats %.3f  write %.3f  peak %.0f MiB" % (
    t["total"], t["decode"], t["solve"], t["detrend"], t["stats"], t["write"], r["peak_memory_mib"]))
PY
done
