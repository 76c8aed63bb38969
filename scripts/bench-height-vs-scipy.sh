#!/usr/bin/env bash
# Normal integration speed against SciPy's DCT Poisson solve (issue 40): the same float32
# Neumann problem (5-point Laplacian, right-hand side from the normals' slopes, DCT-II / DCT-III),
# both on every core of this machine, in the same run, each the median of 7 runs (a virtual
# machine's timings come in two modes a tenth apart). Prints a Markdown table.
# Needs python3 with numpy and scipy (installed with pip into a private folder when missing).
# Run on an idle machine: `scripts/bench-height-vs-scipy.sh [SIDES...]` (default 2048 4096 8192).
set -euo pipefail
cd "$(dirname "$0")/.."
sides=("${@:-2048 4096 8192}")
read -r -a sides <<< "${sides[*]}"
py=python3
if ! $py -c "import numpy, scipy" 2>/dev/null; then
    venv="${TMPDIR:-/tmp}/skinkit-bench-venv"
    [ -x "$venv/bin/python" ] || python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet numpy scipy
    py="$venv/bin/python"
fi
cargo build --release --quiet -p skinkit-height --example timing
ours=target/release/examples/timing
echo "| side | skinkit Neumann (s) | memory beyond input (floats/texel) | SciPy dctn (s) | ratio |"
echo "| ---: | ---: | ---: | ---: | ---: |"
for side in "${sides[@]}"; do
    mine=$("$ours" "$side" neumann 7)
    theirs=$($py scripts/height_scipy.py "$side" 7)
    $py - "$mine" "$theirs" <<'PY'
import json, sys
a, b = json.loads(sys.argv[1]), json.loads(sys.argv[2])
print(f"| {a['side']} | {a['median_s']:.3f} | {a['floats_per_texel']:.2f} | {b['median_s']:.3f} | {b['median_s'] / a['median_s']:.1f}x |")
PY
done
