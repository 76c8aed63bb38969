#!/usr/bin/env bash
# Peak memory and time of the resource policy's refusals (issue 15, the book's "Limits"): each case of
# the reliability probe that aborted or spent gigabytes before refusing, re-run against the
# release binary under `/usr/bin/time`, printed as a Markdown table.
#
#   cargo build --release -p skinkit-cli && bash scripts/limits-probe.sh
#
# The inputs are made in a scratch folder (python3, standard library only) and removed after:
# real PNG bombs (valid zlib streams of zeros), not header-only files, so a reader that decoded
# them would pay for it. Set SKINKIT to use another binary.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SKINKIT:-target/release/skinkit}
[ -x "$bin" ] || { echo "no $bin: build it with cargo build --release -p skinkit-cli" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "needs /usr/bin/time (GNU time) for the peak memory" >&2; exit 1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/skinkit-limits.XXXXXX")
trap 'rm -rf "$work"' EXIT
truth=$PWD/samples/molds/cheek/truth.png

python3 - "$work" <<'EOF'
import struct, sys, zlib
work = sys.argv[1]

def png_of_zeros(path, w, h):
    """An 8-bit grey PNG of zeros, streamed: about 1 MB for 32768x32768."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    z = zlib.compressobj(9)
    row = bytes(w + 1)
    idat = b"".join(z.compress(row) for _ in range(h)) + z.flush()
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", idat))
        f.write(chunk(b"IEND", b""))

png_of_zeros(f"{work}/coverage-32768.png", 32768, 32768)
png_of_zeros(f"{work}/photo-16384.png", 16384, 16384)
EOF
mkdir -p "$work/stack"
for i in 1 2 3 4 5 6 7 8; do cp "$work/photo-16384.png" "$work/stack/0$i.png"; done

layout() { # name size scale extra
  cat > "$work/$1.toml" <<EOF
$4
size = $2
mm_per_texel = 0.05
[[region]]
name = "a"
exemplar = "$truth"
exemplar_mm_per_texel = 0.05
points = [[0.25, 0.5]]
[[region]]
name = "b"
exemplar = "$truth"
exemplar_mm_per_texel = $3
points = [[0.75, 0.5]]
EOF
}
layout d1-1e9 "[512, 256]" 1e9 ""
layout d1-3 "[512, 256]" 3.0 ""
layout d6-coverage "[512, 256]" 0.05 "coverage = \"$work/coverage-32768.png\""
layout d6-limit "[32768, 32768]" 0.05 ""

echo "| case | command | exit | seconds | peak MiB | message |"
echo "| --- | --- | --- | --- | --- | --- |"
probe() { # name, then the arguments
  local name=$1; shift
  set +e
  /usr/bin/time -f "%e %M" -o "$work/time" "$bin" "$@" > /dev/null 2> "$work/err"
  local rc=$?
  set -e
  local secs kb
  read -r secs kb < <(tail -1 "$work/time")
  local msg
  msg=$(grep -v '^Command exited' "$work/err" | head -1 | sed "s|$work/||g; s|$PWD/||g" | cut -c1-150)
  printf '| %s | `skinkit %s` | %s | %s | %s | %s |\n' "$name" "$(echo "$*" | sed "s|$work/||g; s|$PWD/||g")" \
    "$rc" "$secs" "$(awk -v kb="$kb" 'BEGIN { printf "%.0f", kb / 1024 }')" "$msg"
}
probe "D1 exemplar_mm_per_texel = 1e9" stitch --layout "$work/d1-1e9.toml" --out "$work/o.png"
probe "D1 exemplar_mm_per_texel = 3" stitch --layout "$work/d1-3.toml" --out "$work/o.png"
probe "D2 --frames 1e11" render "$work/none.toml" --out "$work/o.png" --orbit --frames 100000000000
probe "D6 coverage 32768^2 (1 MB PNG)" stitch --layout "$work/d6-coverage.toml" --out "$work/o.png"
probe "D6 layout at the size limit" --memory-limit 8G stitch --layout "$work/d6-limit.toml" --out "$work/o.png"
probe "D8 --threads 100000" --threads 100000 rig check calibration/turntable-8.toml
probe "D9 8 photos of 16384^2, limit 4G" --memory-limit 4G capture --rig calibration/turntable-8.toml \
  --out "$work/cap" "$work"/stack/0{1..8}.png
# The second probe's D11: an orbit's memory must not grow with its frames (a Vulkan driver is
# needed: lavapipe here).
source scripts/lavapipe.sh
mkdir -p "$work/orbit"
probe "probe 2 D11 orbit, 100 frames at 8x8" render samples/scenes/head-smooth.toml --out "$work/orbit/o.png" \
  --orbit --frames 100 --size 8x8 --quiet
probe "probe 2 D11 orbit, 3600 frames at 8x8" render samples/scenes/head-smooth.toml --out "$work/orbit/o.png" \
  --orbit --frames 3600 --size 8x8 --quiet
