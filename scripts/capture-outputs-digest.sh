#!/usr/bin/env bash
# SHA-256 of every output of `skinkit capture` on each sample mold (with its truth map) and of
# `skinkit batch` on the samples folder, report.json files without their timings and peak memory.
# Run it with two builds and diff the digests to show a change left the outputs bit for bit:
#   bash scripts/capture-outputs-digest.sh BIN > before.txt; ...; diff before.txt after.txt
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "$1")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for mold in samples/molds/*/; do
  name=$(basename "$mold")
  for solver in robust ls; do
    "$bin" capture --quiet --solver "$solver" --rig "$mold/rig.toml" --photos-from "$mold" \
      --truth "$mold/truth.png" --out "$work/capture/$name-$solver"
  done
done
"$bin" batch --quiet samples/molds --out "$work/batch"
cd "$work"
find . -type f | sort | while read -r f; do
  case "$f" in
    *report.json)
      python3 - "$f" <<'PY'
import hashlib, json, sys
r = json.load(open(sys.argv[1]))
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in ("timings_s", "peak_memory_mib", "seconds")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
print(hashlib.sha256(json.dumps(strip(r), sort_keys=True).encode()).hexdigest() + "  " + sys.argv[1] + " (timings stripped)")
PY
      ;;
    *) sha256sum "$f" ;;
  esac
done
