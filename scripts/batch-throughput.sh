#!/usr/bin/env bash
# What one machine does per hour with `skinkit batch`: COUNT sessions of 8 photos of SIDE x SIDE
# pixels (16-bit, the sample molds of `skinkit samples`), captured by one batch; prints the
# batch report's throughput (sessions a minute, an hour) and the memory gate's use.
#
#   scripts/batch-throughput.sh [SIDE=2048] [COUNT=8] [SKINKIT=target/release/skinkit]
set -euo pipefail
side="${1:-2048}"
count="${2:-8}"
skinkit="${3:-target/release/skinkit}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$skinkit" samples --quiet --size "$side" --out "$work/molds"
regions=(cheek forehead forehead-edge nose)
for i in $(seq 0 $((count - 1))); do
    mkdir -p "$work/sessions/s$i"
    cp "$work/molds/${regions[$((i % 4))]}"/0?.png "$work/molds/${regions[$((i % 4))]}/rig.toml" "$work/sessions/s$i/"
done
"$skinkit" batch --quiet "$work/sessions" --out "$work/maps"
python3 - "$work/maps/batch-report.json" "$side" << 'PY'
import json, sys, os
r = json.load(open(sys.argv[1]))
side = sys.argv[2]
print(f"{r['sessions']} sessions of 8 x {side}x{side} 16-bit photos on {os.cpu_count()} cores: "
      f"{r['seconds']:.1f} s, {r['sessions_per_minute']:.2f} sessions a minute "
      f"({60 * r['sessions_per_minute']:.0f} an hour); {r['most_at_once']} at once, memory gate "
      f"{r['memory_peak_mib']} of {r['memory_limit_mib']} MiB; review page {1000 * r['page_seconds']:.1f} ms")
PY
