#!/usr/bin/env bash
# Regenerates the README's accuracy-against-time section from the full run of `skinkit accuracy`:
# the plots go to docs/accuracy/, and accuracy.md's stage sections (plot links pointed there)
# replace the README's text between <!-- accuracy:start --> and <!-- accuracy:end -->.
# Takes tens of minutes on 2 cores (medians of 3 runs; the rendering stage's references dominate).
#   bash scripts/accuracy-docs.sh [WORK_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-/tmp/skinkit-accuracy}
source scripts/lavapipe.sh
cargo build --release -q -p skinkit-cli
target=${CARGO_TARGET_DIR:-target}
"$target/release/skinkit" accuracy --out "$work"
mkdir -p docs/accuracy
cp "$work"/accuracy-*.png docs/accuracy/
python3 - "$work/accuracy.md" README.md <<'PY'
import re, sys
md, readme = sys.argv[1], sys.argv[2]
body = open(md).read()
# Drop the document's own title; link the plots where the docs keep them.
body = re.sub(r"^# .*\n\n", "", body)
body = re.sub(r"\]\((accuracy-[a-z]+\.png)\)", r"](docs/accuracy/\1)", body)
body = re.sub(r"^## ", "#### ", body, flags=re.M)
text = open(readme).read()
start, end = "<!-- accuracy:start -->", "<!-- accuracy:end -->"
if start not in text or end not in text:
    sys.exit(f"{readme}: no {start} ... {end} markers")
a, b = text.index(start) + len(start), text.index(end)
open(readme, "w").write(text[:a] + "\n" + body + text[b:])
print(f"README accuracy section and docs/accuracy/ updated from {md}")
PY
