#!/usr/bin/env bash
# Fuzzes every parser and decoder entry of skinkit (issue 15) with cargo-fuzz and libFuzzer, one
# target at a time, and writes a summary table.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     # default 60 s, every target
#
# Targets live in fuzz/ (a Cargo workspace of its own, excluded from the main one); their entry
# points are tests/fuzz/entries.rs, shared with the regression tests tests/fuzz_regressions.rs (a
# module of skinkit-cli's test binary `cli`).
#
# Toolchain: libFuzzer needs the sanitizer-coverage flags of a nightly compiler. With a nightly
# toolchain installed (`rustup toolchain list`) the targets build with `cargo +nightly fuzz` and
# AddressSanitizer. Without one (no toolchain can be downloaded on the project's machines), the
# stable compiler is used with RUSTC_BOOTSTRAP=1 and `--sanitizer none`: coverage-guided still,
# but memory errors in unsafe code are then only found when they crash.
# cargo-fuzz itself comes from crates.io: `cargo install cargo-fuzz --locked` (0.13.2 here); the
# script runs that when `cargo fuzz` is missing.
#
# Each run starts from seeds written by the regression test (valid files of every kind, made with
# the project's own writers) plus the corpus kept in fuzz/corpus/<target> from earlier runs.
# libFuzzer limits per input: -rss_limit_mb=2048 (the image targets accept at most 2048x2048
# pixels, 64 MiB as RGBA float, see FUZZ_LIMITS), -timeout=10 s, -max_len by kind below.
# A crash, timeout or out-of-memory input is copied to tests/fuzz-regressions/<target>/, where
# `cargo test -p skinkit-cli --test cli fuzz_regressions::` replays it until the bug is fixed.
#
# Output: one line per target (time, executions, crashes) and docs/fuzz-summary.tsv with columns
# target, seconds, executions, execs_per_second, crashes, corpus, max_len, toolchain, load, date.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
seconds="${1:-60}"
shift || true
all_targets=(rig_toml diligent_lights uw_lights layout scene obj gltf photo normal_map coverage_mask coords lut_file)
if [ "$#" -gt 0 ]; then targets=("$@"); else targets=("${all_targets[@]}"); fi

max_len() {
    case "$1" in
        photo | normal_map | coverage_mask | coords | lut_file) echo 65536 ;;
        *) echo 16384 ;;
    esac
}

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "cargo-fuzz is missing: cargo install cargo-fuzz --locked" >&2
    cargo install cargo-fuzz --locked
fi
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
    fuzz=(cargo +nightly fuzz)
    sanitizer=(--sanitizer address)
    toolchain="nightly+asan"
else
    export RUSTC_BOOTSTRAP=1
    fuzz=(cargo fuzz)
    sanitizer=(--sanitizer none)
    toolchain="stable+RUSTC_BOOTSTRAP"
fi
# The fuzz targets build in their own folder (SKINKIT_FUZZ_TARGET_DIR, default target/fuzz): a
# nightly sanitizer build shares nothing with the workspace's, and a folder of its own lets it run
# beside a workspace build without waiting on that build's lock.
fuzz_target_dir="${SKINKIT_FUZZ_TARGET_DIR:-$root/target/fuzz}"
fuzz=(env CARGO_TARGET_DIR="$fuzz_target_dir" "${fuzz[@]}")

echo "load before: $(uptime)"
echo "building ${#targets[@]} targets ($toolchain, debug assertions on)..."
build_start=$(date +%s)
"${fuzz[@]}" build "${sanitizer[@]}" --debug-assertions
echo "built in $(($(date +%s) - build_start)) s"

seeds="$(mktemp -d)"
trap 'rm -rf "$seeds"' EXIT
# SKINKIT_FUZZ_SKIP_SEEDS=1 skips this step (it builds the regression test): the corpora kept in
# fuzz/corpus/ and the repository's sample files are used alone then.
if [ -z "${SKINKIT_FUZZ_SKIP_SEEDS:-}" ]; then
    # `--workspace`, as the test command builds it: `-p` would resolve other features and rebuild.
    SKINKIT_FUZZ_SEEDS="$seeds" cargo test -q --workspace --test cli fuzz_regressions::valid_inputs -- --nocapture >/dev/null
else
    mkdir -p "$seeds"/{rig_toml,layout,scene}
    cp calibration/*.toml samples/molds/*/rig.toml "$seeds/rig_toml/" 2>/dev/null || true
    cp samples/face/layout.toml "$seeds/layout/"
    cp samples/scenes/*.toml "$seeds/scene/"
fi

summary="docs/fuzz-summary.tsv"
tmp_summary="$(mktemp)"
printf 'target\tseconds\texecutions\texecs_per_second\tcrashes\tcorpus\tmax_len\ttoolchain\tload\tdate\n' >"$tmp_summary"
printf '%-16s %8s %12s %8s\n' target seconds executions crashes
for t in "${targets[@]}"; do
    corpus="fuzz/corpus/$t"
    artifacts="fuzz/artifacts/$t"
    mkdir -p "$corpus" "$artifacts"
    cp -n "$seeds/$t"/* "$corpus"/ 2>/dev/null || true
    before=$(find "$artifacts" -type f | wc -l)
    log="$(mktemp)"
    marker="$(mktemp)"
    start=$(date +%s.%N)
    set +e
    "${fuzz[@]}" run "${sanitizer[@]}" --debug-assertions "$t" "$corpus" -- \
        -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -max_len="$(max_len "$t")" \
        -print_final_stats=1 -artifact_prefix="$artifacts/" >"$log" 2>&1
    set -e
    elapsed=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    runs=${runs:-$(grep -o 'Done [0-9]* runs' "$log" | grep -o '[0-9]*' | tail -1)}
    runs=${runs:-0}
    found=$(($(find "$artifacts" -type f | wc -l) - before))
    if [ "$found" -gt 0 ]; then
        mkdir -p "tests/fuzz-regressions/$t"
        find "$artifacts" -type f -newer "$marker" -exec cp {} "tests/fuzz-regressions/$t/" \;
        echo "  $t: $found new crash input(s), log kept at $log; copied to tests/fuzz-regressions/$t/" >&2
        grep -m3 -E 'panicked|ERROR|SUMMARY' "$log" >&2 || true
    else
        rm -f "$log"
    fi
    rm -f "$marker"
    rate=$(awk -v r="$runs" -v s="$elapsed" 'BEGIN { printf "%.0f", r / s }')
    printf '%-16s %8.0f %12s %8s\n' "$t" "$elapsed" "$runs" "$found"
    printf '%s\t%.0f\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$t" "$elapsed" "$runs" "$rate" "$found" \
        "$(find "$corpus" -type f | wc -l)" "$(max_len "$t")" "$toolchain" \
        "$(cut -d' ' -f1 /proc/loadavg)" "$(date -u +%Y-%m-%dT%H:%M:%SZ)" >>"$tmp_summary"
    # Rows so far, so an interrupted run still leaves the targets it finished.
    cp "$tmp_summary" "$summary.partial"
done
rm -f "$summary.partial"
# A run of some targets replaces their rows and keeps the others'.
if [ -f "$summary" ] && [ "${#targets[@]}" -lt "${#all_targets[@]}" ]; then
    merged="$(mktemp)"
    head -1 "$tmp_summary" >"$merged"
    for t in "${all_targets[@]}"; do
        grep -P "^$t\t" "$tmp_summary" || grep -P "^$t\t" "$summary" || true
    done >>"$merged"
    mv "$merged" "$tmp_summary"
fi
mv "$tmp_summary" "$summary"
echo "load after: $(uptime)"
echo "summary: $summary"
