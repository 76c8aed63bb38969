#!/usr/bin/env bash
# Re-runs the hostile cases of issue 15's reliability probe (every row it marked defect or risk)
# against a skinkit binary, and checks each the same way:
#   exit    the expected exit code (0 success, 1 an input or job failed, 2 a usage error,
#           130 interrupted; `0|1` where either is right, e.g. a job a memory budget may refuse);
#   line    a failure prints one line, `error: ...`, naming the file once, no OS error twice,
#           and matching the case's pattern where it has one;
#   out     nothing is left at the output path of a failed run (or the folder is as it was);
#   temp    no hidden or temporary file anywhere in the scratch tree;
#   inputs  every input unchanged (sha256 of every file of the inputs before and after);
#   memory  peak resident memory under the case's bound, where it has one (cheap refusals).
# Inputs are made in a scratch folder by the binary itself, the shell and
# scripts/hostile_inputs.py (python3, standard library only). Each run is under `timeout` and an
# address-space cap. Results: one TSV line per case (scripts/hostile-table.py turns them into the
# book's table, docs/book/src/scripts.md); a summary at the end. It mounts tmpfs for the full-disk rows when run as root
# (skipped otherwise). CI runs it with --quick on the debug binary its tests built.
#
# usage: scripts/hostile.sh [--bin PATH] [--results FILE] [--only REGEX] [--quick] [--keep]
#   --bin      the binary (default: target/release/skinkit; build it with
#              `cargo build --release -p skinkit-cli`)
#   --results  the TSV to write (default: target/hostile/results.tsv)
#   --only     run only the rows whose number matches REGEX (e.g. '^5\.')
#   --quick    skip the rows that decode gigabytes of photos (1.10, 6.10) and the 40-session
#              re-run (6.4), each minutes in a debug build, and make no inputs for them
#   --keep     keep the scratch folder
set -uo pipefail
cd "$(dirname "$0")/.."
REPO=$(pwd)
BIN=$REPO/target/release/skinkit
RESULTS=$REPO/target/hostile/results.tsv
KEEP=0
ONLY=
QUICK=0
while [ $# -gt 0 ]; do
    case $1 in
        --bin) BIN=$(realpath "$2"); shift 2 ;;
        --results) RESULTS=$(realpath -m "$2"); shift 2 ;;
        --keep) KEEP=1; shift ;;
        --only) ONLY=$2; shift 2 ;;
        --quick) QUICK=1; shift ;;
        *) echo "usage: $0 [--bin PATH] [--results FILE] [--only REGEX] [--quick] [--keep]" >&2; exit 2 ;;
    esac
done
[ -x "$BIN" ] || { echo "$0: no binary at $BIN (cargo build --release -p skinkit-cli)" >&2; exit 2; }
command -v python3 > /dev/null || { echo "$0: python3 is needed to make the inputs" >&2; exit 2; }
MK="python3 $REPO/scripts/hostile_inputs.py"
[ -f "$REPO/scripts/lavapipe.sh" ] && source "$REPO/scripts/lavapipe.sh"
export RUST_BACKTRACE=0

SCRATCH=$(mktemp -d "${TMPDIR:-/tmp}/skinkit-hostile.XXXXXX")
chmod 755 "$SCRATCH"
IN=$SCRATCH/in     # every input; hashed before and after each case
OUT=$SCRATCH/out   # outputs of the cases, emptied after each
LOG=$SCRATCH/log   # stdout/stderr of the current case
mkdir -p "$IN" "$OUT" "$LOG" "$(dirname "$RESULTS")"
export XDG_RUNTIME_DIR=$SCRATCH/xdg
mkdir -m 700 "$XDG_RUNTIME_DIR"
MOUNTS=()
cleanup() {
    for m in "${MOUNTS[@]}"; do umount "$m" 2> /dev/null; done
    if [ "$KEEP" = 1 ]; then echo "scratch kept: $SCRATCH" >&2; else rm -rf "$SCRATCH"; fi
}
trap cleanup EXIT
printf '# binary %s (%s), %s, load %s\n' "$BIN" "$(git -C "$REPO" rev-parse --short HEAD 2> /dev/null || echo unknown)" \
    "$(date -u +%Y-%m-%dT%H:%MZ)" "$(cut -d' ' -f1-3 /proc/loadavg 2> /dev/null)" > "$RESULTS"
printf 'row\tdefect\tcase\twant\tgot\tseconds\tpeak_mib\texit\tline\tout\ttemp\tinputs\tmemory\tverdict\tnote\n' >> "$RESULTS"
PASS=0; FAIL=0; SKIP=0

selected() { [ -z "$ONLY" ] || [[ $1 =~ $ONLY ]]; }

# slow ROW DEFECT CASE: true (and the row recorded as skipped) when --quick leaves ROW out.
slow() {
    [ "$QUICK" = 1 ] || return 1
    selected "$1" && skip "$1" "$2" "$3" "left out by --quick (minutes in a debug build)"
    return 0
}

# hash_inputs FILE: the sha256 of every regular file under $IN, one line each in path order; a
# file of several hard links (the batch sessions share their photos) is read once.
hash_inputs() {
    python3 - "$IN" > "$1" << 'EOF'
import hashlib, os, stat, sys
seen = {}
for root, dirs, files in os.walk(sys.argv[1]):
    dirs.sort()
    for name in sorted(files):
        path = os.path.join(root, name)
        st = os.lstat(path)
        if not stat.S_ISREG(st.st_mode):
            continue
        key = (st.st_dev, st.st_ino)
        if key not in seen:
            digest = hashlib.sha256()
            with open(path, "rb") as f:
                for block in iter(lambda: f.read(1 << 20), b""):
                    digest.update(block)
            seen[key] = digest.hexdigest()
        print(seen[key], os.path.relpath(path, sys.argv[1]))
EOF
}
hidden_files() { find "$SCRATCH" -mindepth 1 -name '.*' -not -path "$XDG_RUNTIME_DIR*" | head -3; }

# record ROW DEFECT CASE WANT GOT SECONDS PEAK EXIT LINE OUTS TEMP INPUTS MEMORY NOTE
record() {
    local verdict=pass
    for check in "$8" "$9" "${10}" "${11}" "${12}" "${13}"; do
        [ "$check" = fail ] && verdict=fail
    done
    [ "$verdict" = pass ] && PASS=$((PASS + 1)) || FAIL=$((FAIL + 1))
    local note=${14//$'\t'/ }
    note=${note//$SCRATCH/S}
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$4" "$5" "$6" "$7" \
        "$8" "$9" "${10}" "${11}" "${12}" "${13}" "$verdict" "${note:0:300}" >> "$RESULTS"
    printf '%-5s %-4s %-4s want %-5s got %-4s %6ss  %s\n' "$1" "$2" "$verdict" "$4" "$5" "$6" "${note:0:110}"
}

skip() { # skip ROW DEFECT CASE REASON
    SKIP=$((SKIP + 1))
    printf '%s\t%s\t%s\t-\t-\t-\t-\t-\t-\t-\t-\t-\t-\tskip\t%s\n' "$1" "$2" "$3" "$4" >> "$RESULTS"
    printf '%-5s %-4s skip  %s\n' "$1" "$2" "$4"
}

# run_bin ARGS: runs the binary under timeout ($T s), an address-space cap ($AS KiB), as the user
# $RUN_AS when set, and under /usr/bin/time when present; sets RC, SECONDS_TAKEN, PEAK (MiB or -).
run_bin() {
    local start end as_user=() timer=()
    [ -n "${RUN_AS:-}" ] && as_user=(setpriv "--reuid=$RUN_AS" "--regid=$RUN_AS" --clear-groups)
    [ -x /usr/bin/time ] && timer=(/usr/bin/time -f %M -o "$LOG/rss")
    start=$(date +%s.%N)
    ( ulimit -v "${AS:-16000000}"; exec "${timer[@]}" timeout -s KILL "${T:-60}" "${as_user[@]}" "$BIN" "$@" ) \
        > "$LOG/stdout" 2> "$LOG/stderr"
    RC=$?
    end=$(date +%s.%N)
    SECONDS_TAKEN=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')
    PEAK=-
    if [ -s "$LOG/rss" ]; then PEAK=$(( $(tail -1 "$LOG/rss" | tr -dc 0-9) / 1024 )); fi
    rm -f "$LOG/rss"
    # /usr/bin/time reports a signal death as its own line and exit 128+N; keep the code only.
    sed -i '/^Command \(terminated by signal\|exited with non-zero status\)/d' "$LOG/stderr"
}

# check_line NAME PATTERN: one `error:` line naming NAME once (NAME - : no file to name), no OS
# error twice, matching the extended regex PATTERN (- : none). Sets LINE_OK and NOTE.
check_line() {
    local name=$1 pattern=$2 lines line
    lines=$(grep -v '^warning: \|XDG_RUNTIME_DIR\|^\s*$' "$LOG/stderr")
    # A usage error (2) is clap's: its first line is the error, then help follows.
    [ "$RC" = 2 ] && lines=$(printf '%s\n' "$lines" | head -1)
    # A batch reports each failed session as a warning line; check the first.
    [ -n "${MULTI:-}" ] && [ -z "$lines" ] && lines=$(grep -m1 '^warning: ' "$LOG/stderr" | sed 's/^warning: /error: /')
    line=$(printf '%s\n' "$lines" | head -1)
    NOTE=$line
    LINE_OK=pass
    if [ "$(printf '%s\n' "$lines" | grep -c .)" != 1 ] || [[ $line != error:* ]]; then
        LINE_OK=fail; NOTE="not one error line: $(head -c 300 "$LOG/stderr" | tr '\n' '|')"; return
    fi
    if [ "$name" != - ] && [ "$(grep -o -F -- "$name" <<< "$line" | wc -l)" != 1 ]; then
        LINE_OK=fail; NOTE="does not name $(basename -- "$name") once: $line"; return
    fi
    if grep -q '\.tmp' <<< "$line"; then LINE_OK=fail; NOTE="temp file named: $line"; return; fi
    if [ -n "$(grep -o '(os error [0-9]*)' <<< "$line" | sort | uniq -d)" ]; then
        LINE_OK=fail; NOTE="OS error repeated: $line"; return
    fi
    if [ "$pattern" != - ] && ! grep -Eq -- "$pattern" <<< "$line"; then
        LINE_OK=fail; NOTE="lacks /$pattern/: $line"
    fi
}

# hcase ROW DEFECT CASE WANT NAME PATTERN OUTPATH -- ARGS...
#   WANT: exit codes separated by | ; NAME: what the error must name once (- : nothing);
#   PATTERN: extended regex for the error line, or for stderr when the case should succeed
#   (- : none); OUTPATH: must not exist after a failed run (- : none).
#   Optional environment: T (timeout s), AS (KiB), MAXMB (peak bound), MAXSEC (time bound).
hcase() {
    local row=$1 defect=$2 what=$3 want=$4 name=$5 pattern=$6 outpath=$7
    shift 8
    selected "$row" || return 0
    hash_inputs "$LOG/before"
    run_bin "$@"
    hash_inputs "$LOG/after"
    local exit_ok=fail line_ok=- out_ok=- temp_ok=pass inputs_ok=pass memory_ok=- note
    [[ "|$want|" == *"|$RC|"* ]] && exit_ok=pass
    if [ "$RC" = 0 ]; then
        note=$(grep -v XDG_RUNTIME_DIR "$LOG/stderr" | head -1)
        if [ "$pattern" != - ]; then
            line_ok=pass
            grep -Eq -- "$pattern" "$LOG/stderr" || { line_ok=fail; note="stderr lacks /$pattern/"; }
        fi
    else
        check_line "$name" "$pattern"; line_ok=$LINE_OK; note=$NOTE
        if [ "$outpath" != - ]; then
            out_ok=pass
            [ -e "$outpath" ] && { out_ok=fail; note="left $(basename -- "$outpath"); $note"; }
        fi
    fi
    [ "$RC" = 137 ] && note="killed after ${T:-60} s; $note"
    [ "$RC" = 134 ] && note="aborted: $(grep -m1 'memory allocation' "$LOG/stderr" || true) $note"
    local hidden
    hidden=$(hidden_files)
    [ -n "$hidden" ] && { temp_ok=fail; note="hidden files: ${hidden//$'\n'/ }; $note"; }
    cmp -s "$LOG/before" "$LOG/after" || { inputs_ok=fail; note="inputs changed: $(diff "$LOG/before" "$LOG/after" | grep -m1 '^>' ); $note"; }
    if [ -n "${MAXMB:-}" ]; then
        memory_ok=pass
        if [ "$PEAK" = - ] || [ "$PEAK" -gt "$MAXMB" ]; then memory_ok=fail; note="peak ${PEAK} MiB > ${MAXMB}; $note"; fi
    fi
    if [ -n "${MAXSEC:-}" ] && awk -v a="$SECONDS_TAKEN" -v b="$MAXSEC" 'BEGIN { exit !(a > b) }'; then
        exit_ok=fail; note="took ${SECONDS_TAKEN} s > ${MAXSEC}; $note"
    fi
    record "$row" "$defect" "$what" "$want" "$RC" "$SECONDS_TAKEN" "$PEAK" "$exit_ok" "$line_ok" "$out_ok" \
        "$temp_ok" "$inputs_ok" "$memory_ok" "$note"
    find "$OUT" -mindepth 1 -delete 2> /dev/null || rm -rf "${OUT:?}"/*
}

source "$REPO/scripts/hostile-cases.sh"

echo "inputs in $SCRATCH"
make_inputs
run_cases
total=$((PASS + FAIL))
echo
echo "$total cases: $PASS passed, $FAIL failed, $SKIP skipped (results: $RESULTS)"
[ "$FAIL" = 0 ]
