# The cases of scripts/hostile.sh (sourced by it): the rows of issue 15's reliability probe marked
# defect or risk, numbered as the probe numbers them, with what each should give now.
# Helpers and variables (hcase, run_bin, record, skip, IN, OUT, BIN, MK, ...) come from hostile.sh.

# A 2-region layout of size SIZE (e.g. `512, 256`) grown from the cheek and nose truth maps,
# exemplar scale SCALE, and EXTRA lines at the top.
write_layout() {
    local path=$1 size=$2 scale=$3 extra=${4:-}
    cat > "$path" << EOF
size = [$size]
mm_per_texel = 0.05
$extra
[[region]]
name = "cheek"
exemplar = "$IN/molds/cheek/truth.png"
exemplar_mm_per_texel = $scale
points = [[0.3, 0.5]]
[[region]]
name = "nose"
exemplar = "$IN/molds/nose/truth.png"
exemplar_mm_per_texel = $scale
points = [[0.7, 0.5]]
EOF
}

# A scene of the head mesh MESH, with BODY (maps) added, a 32x24 output.
write_scene() {
    local path=$1 mesh=$2 body=${3:-}
    cat > "$path" << EOF
mesh = "$mesh"
mm_per_unit = 1.0
$body
[[light]]
kind = "directional"
direction = [0.75, 0.35, 0.55]
[[camera]]
position = [170.0, 25.0, 380.0]
target = [0.0, 5.0, 0.0]
[output]
size = [32, 24]
EOF
}

# A session folder DIR of COUNT copies of photo FILE (01.png, ...) with rig RIG.
photo_folder() {
    local dir=$1 file=$2 count=$3 rig=$4 i
    mkdir -p "$dir"
    for i in $(seq -f '%03g' 1 "$count"); do cp "$file" "$dir/$i.png"; done
    cp "$rig" "$dir/rig.toml"
}

make_inputs() {
    "$BIN" samples --quiet --size 256 --out "$IN/molds" || { echo "skinkit samples failed" >&2; exit 1; }
    "$BIN" samples --quiet --head "$IN/head/head.obj" --head-only || { echo "skinkit samples --head failed" >&2; exit 1; }
    C=$IN/molds/cheek
    RIG=$C/rig.toml
    PHOTOS=("$C"/0[1-8].png)
    # 1.10: eight photos at the per-photo cap (16384x16384 8-bit grey, 290 KB each).
    if [ "$QUICK" = 0 ]; then
        $MK gray8 "$IN/big.png" 16384 16384 100
        photo_folder "$IN/capped" "$IN/big.png" 8 "$RIG"
        rm "$IN/big.png"
    fi
    # 1.12: eight JPEG photos named .png.
    mkdir -p "$IN/jpeg"
    for i in 1 2 3 4 5 6 7 8; do $MK jpeg "$IN/jpeg/0$i.png" 256 256 "$i"; done
    cp "$RIG" "$IN/jpeg/rig.toml"
    mkdir -p "$IN/folder-photo/03.png"
    # Section 2: rigs.
    mkdir -p "$IN/rigs"
    for kind in rank2 coplanar near-coplanar lights200 ambient positions; do $MK rig "$IN/rigs/$kind.toml" "$kind"; done
    $MK bytes "$IN/rigs/noise.toml" 2000 16
    $MK gray16 "$IN/small.png" 8 8 30000
    photo_folder "$IN/p200" "$IN/small.png" 200 "$IN/rigs/lights200.toml"
    rm "$IN/small.png"
    mkdir -p "$IN/diligent"
    printf '0 0 1\n0.5 0 0.8\n0 0.5 0.8\n' > "$IN/diligent/light_directions.txt"
    # Section 3: layouts.
    mkdir -p "$IN/layouts"
    write_layout "$IN/layouts/huge.toml" "32768, 32768" 0.02
    write_layout "$IN/layouts/scale1e9.toml" "512, 256" 1e9
    write_layout "$IN/layouts/scale3.toml" "512, 256" 3.0
    $MK gray8 "$IN/layouts/coverage.png" 32768 32768 0
    write_layout "$IN/layouts/coverage.toml" "512, 256" 0.02 "coverage = \"$IN/layouts/coverage.png\""
    # Section 4: exemplars.
    mkdir -p "$IN/exemplars"
    $MK rgb16-random "$IN/exemplars/random.png" 64 64 7
    $MK rgb16-const "$IN/exemplars/invalid.png" 64 64 0 0 0
    cp "$C/truth.png" "$IN/exemplars/truth.png"
    # Section 5: meshes and scenes.
    local H=$IN/head/head.obj S=$IN/scenes
    mkdir -p "$S"
    # Every 50th `v` line NaN; the file line of the first is what the error must give.
    awk '/^v / { n++; if (n % 50 == 0) { print "v nan nan nan"; next } } { print }' "$H" > "$S/nan.obj"
    NAN_LINE=$(grep -n -m1 '^v nan' "$S/nan.obj" | cut -d: -f1)
    cp "$H" "$S/far.obj"
    echo 'f 1/1/1 2/2/2 99999/3/3' >> "$S/far.obj"
    FAR_LINE=$(wc -l < "$S/far.obj")
    $MK gltf "$S/overrun.gltf" overrun
    $MK gltf "$S/offset.gltf" offset
    $MK gray16 "$S/grey.png" 64 64 30000
    $MK gray8 "$S/bomb.png" 100000 1 0
    # A PNG header claiming 100000x100000 (the rest cut off): refused from the header.
    head -c 33 "$S/bomb.png" > "$S/bomb-header.png" && rm "$S/bomb.png"
    python3 - "$S/bomb-header.png" << 'EOF'
import struct, sys, zlib
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
b[16:24] = struct.pack(">II", 100000, 100000)
b[29:33] = struct.pack(">I", zlib.crc32(bytes(b[12:29])) & 0xFFFFFFFF)
open(p, "wb").write(bytes(b))
EOF
    write_scene "$S/no-mesh.toml" "$S/nope.obj"
    write_scene "$S/nan.toml" "$S/nan.obj"
    write_scene "$S/far.toml" "$S/far.obj"
    write_scene "$S/overrun.toml" "$S/overrun.gltf"
    write_scene "$S/offset.toml" "$S/offset.gltf"
    write_scene "$S/nm-missing.toml" "$H" "[normal_map]
path = \"$S/nope.png\""
    write_scene "$S/nm-toml.toml" "$H" "[normal_map]
path = \"$S/nan.toml\""
    write_scene "$S/nm-grey.toml" "$H" "[normal_map]
path = \"$S/grey.png\""
    write_scene "$S/nm-bomb.toml" "$H" "[normal_map]
path = \"$S/bomb-header.png\""
    write_scene "$S/albedo-missing.toml" "$H" "albedo = \"$S/nope.png\""
    cp "$C/truth.png" "$S/map.png"
    write_scene "$S/head.toml" "$H" "[normal_map]
path = \"$S/map.png\""
    # Section 6: batches.
    # 6.3: 40 sessions of the molds at 1024x1024 (hard links: 89 MB once), about 6 s of batch in
    # a release build; --quick (a debug build) takes the 256x256 molds, as long a batch there.
    local molds40=$IN/molds
    if [ "$QUICK" = 0 ]; then
        molds40=$IN/molds1024
        "$BIN" samples --quiet --size 1024 --out "$molds40" || { echo "skinkit samples failed" >&2; exit 1; }
    fi
    mkdir -p "$IN/batch40"
    local k=0 m
    for i in $(seq 1 10); do
        for m in cheek forehead forehead-edge nose; do
            k=$((k + 1))
            cp -al "$molds40/$m" "$IN/batch40/$(printf 's%02d' "$k")-$m"
        done
    done
    mkdir -p "$IN/batch4"
    for m in cheek forehead forehead-edge nose; do cp -al "$IN/molds/$m" "$IN/batch4/$m"; done
    if [ "$QUICK" = 0 ]; then
        $MK gray8 "$IN/b8k.png" 8192 8192 100
        photo_folder "$IN/big2/a" "$IN/b8k.png" 8 "$RIG"
        photo_folder "$IN/big2/b" "$IN/b8k.png" 8 "$RIG"
        rm "$IN/b8k.png"
    fi
    # Section 7: same-path cases work on copies (the hashes say whether they survived).
    mkdir -p "$IN/same/photos" "$IN/same/diligent" "$IN/same/sessions"
    cp "$C/truth.png" "$IN/same/exemplar.png"
    cp "$C"/0[1-8].png "$C/rig.toml" "$IN/same/photos/"
    cp -r "$C" "$IN/same/sessions/cheek"
    printf '0 0 1\n0.5 0 0.8\n0 0.5 0.8\n' > "$IN/same/diligent/light_directions.txt"
    printf '1 1 1\n1 1 1\n1 1 1\n' > "$IN/same/diligent/light_intensities.txt"
    write_scene "$IN/same/scene.toml" "$H" "[normal_map]
path = \"$IN/same/exemplar.png\""
}

capture_with() { # capture_with RIG OUT PHOTO... : the capture command line
    local rig=$1 out=$2
    shift 2
    echo capture --rig "$rig" --out "$out" "$@"
}

run_cases() {
    local R=$IN/rigs S=$IN/scenes
    local -a P=("${PHOTOS[@]}")
    # 1. Images.
    slow 1.10 D9 "8 photos at the per-photo cap (2.3 MB of PNGs)" \
        || T=150 AS=12000000 hcase 1.10 D9 "8 photos at the per-photo cap (2.3 MB of PNGs)" "0|1" "$IN/capped" - \
        "$OUT/capped" -- capture --rig "$IN/capped/rig.toml" --photos-from "$IN/capped" --out "$OUT/capped"
    hcase 1.12 D13 "all 8 photos JPEG data named .png" 1 "$IN/jpeg/0" "JPEG.*linear" "$OUT/jpeg" -- \
        capture --rig "$IN/jpeg/rig.toml" --photos-from "$IN/jpeg" --out "$OUT/jpeg"
    hcase 1.22a D10 "photo 3 is a folder" 1 "$IN/folder-photo/03.png" "photo 3" "$OUT/c" -- \
        capture --rig "$RIG" --out "$OUT/c" "${P[0]}" "${P[1]}" "$IN/folder-photo/03.png" "${P[@]:3}"
    T=20 hcase 1.22b D10 "photo 3 is /dev/zero" 1 /dev/zero "photo 3" "$OUT/c" -- \
        capture --rig "$RIG" --out "$OUT/c" "${P[0]}" "${P[1]}" /dev/zero "${P[@]:3}"
    hcase 1.23 exit "--saturation 0 (a bad flag value)" 2 "--saturation" - "$OUT/c" -- \
        capture --rig "$RIG" --photos-from "$C" --out "$OUT/c" --saturation 0
    T=30 hcase 1.24 D8 "--threads 10000 on a 0.03 s capture" "0|2" "--threads" - - -- \
        --threads 10000 capture --rig "$RIG" --photos-from "$C" --out "$OUT/c"
    # 2. Rigs.
    hcase 2.6 D11 "rig check: rank 2 (repeated directions)" 1 "$R/rank2.toml" - - -- rig check "$R/rank2.toml"
    hcase 2.7a D11 "rig check: coplanar lights" 1 "$R/coplanar.toml" - - -- rig check "$R/coplanar.toml"
    hcase 2.7b D11 "capture: coplanar lights" 1 "$R/coplanar.toml" - "$OUT/c" -- \
        capture --rig "$R/coplanar.toml" --photos-from "$C" --out "$OUT/c"
    hcase 2.8a D7 "rig check: condition number over capture's limit" 1 "$R/near-coplanar.toml" "condition" - -- \
        rig check "$R/near-coplanar.toml"
    hcase 2.8b D11 "capture: condition number over the limit" 1 "$R/near-coplanar.toml" "condition" "$OUT/c" -- \
        capture --rig "$R/near-coplanar.toml" --photos-from "$C" --out "$OUT/c"
    hcase 2.10a D7 "rig check: 200 lights" 1 "$R/lights200.toml" "128" - -- rig check "$R/lights200.toml"
    hcase 2.10b D11 "capture: 200 lights, 200 photos" 1 "$IN/p200/rig.toml" "128" "$OUT/c" -- \
        capture --rig "$IN/p200/rig.toml" --photos-from "$IN/p200" --out "$OUT/c"
    hcase 2.16 D10 "rig check: 2000 random bytes" 1 "$R/noise.toml" - - -- rig check "$R/noise.toml"
    hcase 2.17a D7 "rig check: ambient = a missing file" 1 "$R/ambient.toml" "ambient" - -- rig check "$R/ambient.toml"
    hcase 2.17b D11 "capture: ambient = a missing file" 1 "$R/ambient.toml" "ambient" "$OUT/c" -- \
        capture --rig "$R/ambient.toml" --photos-from "$C" --out "$OUT/c"
    hcase 2.18a D7 "rig check: lights at position (0, 0, 0)" 1 "$R/positions.toml" "position" - -- \
        rig check "$R/positions.toml"
    hcase 2.18b D11 "capture: lights at position (0, 0, 0)" 1 "$R/positions.toml" "position" "$OUT/c" -- \
        capture --rig "$R/positions.toml" --photos-from "$C" --out "$OUT/c"
    hcase 2.25 D10 "DiLiGenT folder without light_intensities.txt" 1 "light_intensities.txt" - "$OUT/r.toml" -- \
        rig import --diligent "$IN/diligent" --out "$OUT/r.toml"
    # 3. Layouts.
    T=120 MAXMB=1024 hcase 3.10 D6 "layout of 32768x32768 (the size limit)" 1 "$IN/layouts/huge.toml" - \
        "$OUT/f.png" -- stitch --layout "$IN/layouts/huge.toml" --out "$OUT/f.png"
    MAXMB=1024 hcase 3.14 D1 "exemplar_mm_per_texel = 1e9" 1 "$IN/layouts/scale1e9.toml" - "$OUT/f.png" -- \
        stitch --layout "$IN/layouts/scale1e9.toml" --out "$OUT/f.png"
    MAXMB=1024 hcase 3.15 D1 "exemplar_mm_per_texel = 3" 1 "$IN/layouts/scale3.toml" - "$OUT/f.png" -- \
        stitch --layout "$IN/layouts/scale3.toml" --out "$OUT/f.png"
    MAXMB=1024 hcase 3.19 D6 "coverage: a 1 MB PNG of 32768x32768" 1 "$IN/layouts/coverage.png" - "$OUT/f.png" -- \
        stitch --layout "$IN/layouts/coverage.toml" --out "$OUT/f.png"
    # 4. synth.
    hcase 4.6 D13 "random RGB exemplar (some texels invalid): a grown map over 1 % invalid fails (issue 42, D6)" 1 - "invalid" - -- \
        synth "$IN/exemplars/random.png" --size 64x64 --out "$OUT/s.png"
    MAXSEC=5 hcase 4.9 D13 "exemplar with every normal invalid" 1 "$IN/exemplars/invalid.png" "no valid normal" \
        "$OUT/s.png" -- synth "$IN/exemplars/invalid.png" --size 128x128 --out "$OUT/s.png"
    # 5. render.
    hcase 5.2 D11 "mesh file missing" 1 "$S/no-mesh.toml" "mesh" "$OUT/r.png" -- render "$S/no-mesh.toml" --out "$OUT/r.png"
    hcase 5.4 D12 "OBJ: NaN on every 50th v line" 1 "$S/nan.obj" "line $NAN_LINE:" "$OUT/r.png" -- \
        render "$S/nan.toml" --out "$OUT/r.png"
    hcase 5.8 D12 "OBJ: face index 99999" 1 "$S/far.obj" "line $FAR_LINE:.*99999" "$OUT/r.png" -- \
        render "$S/far.toml" --out "$OUT/r.png"
    hcase 5.11a D12 "glTF: POSITION count 1e6 over a 36-byte view" 1 "$S/overrun.gltf" "accessor 0" "$OUT/r.png" -- \
        render "$S/overrun.toml" --out "$OUT/r.png"
    hcase 5.11b D12 "glTF: bufferView offset past the buffer" 1 "$S/offset.gltf" "bufferView 2" "$OUT/r.png" -- \
        render "$S/offset.toml" --out "$OUT/r.png"
    local nm row=(5.14a 5.14b 5.14c 5.14d) i=0
    for nm in missing toml grey bomb; do
        hcase "${row[$i]}" D11 "normal map: $nm" 1 "$S/nm-$nm.toml" "normal_map.path" "$OUT/r.png" -- \
            render "$S/nm-$nm.toml" --out "$OUT/r.png"
        i=$((i + 1))
    done
    hcase 5.14e D11 "albedo missing" 1 "$S/albedo-missing.toml" "albedo" "$OUT/r.png" -- \
        render "$S/albedo-missing.toml" --out "$OUT/r.png"
    hcase 5.23 exit "--orbit --frames 0" 2 "--frames" - "$OUT/r.png" -- \
        render "$S/head.toml" --orbit --frames 0 --out "$OUT/r.png"
    T=30 hcase 5.24 D2 "--orbit --frames 100000000000" "1|2" "--frames" - "$OUT/r.png" -- \
        render "$S/head.toml" --orbit --frames 100000000000 --out "$OUT/r.png"
    # 6. Batch.
    interrupts
    full_disk
    report_is_a_folder
    slow 6.10 D9 "batch of 2 sessions of 8 x 8192^2 photos" \
        || T=150 hcase 6.10 D9 "batch of 2 sessions of 8 x 8192^2 photos" "0|1" - - - -- batch "$IN/big2" --out "$OUT/big2"
    # 7. Output collisions.
    mkdir -p "$OUT/dir.png" "$OUT/dir.toml"
    # Each found at start-up (D14): well under the 2-6 s each run takes before its write; a usage
    # error (exit 2), as an output that is an input (D5) is.
    local dir_cases=(
        "7.2a|synth|synth $IN/exemplars/truth.png --size 384x384 --out $OUT/dir.png"
        "7.2b|stitch|stitch --layout $IN/layouts/scale3.toml --size 256x128 --out $OUT/dir.png"
        "7.2c|render|render $S/head.toml --out $OUT/dir.png"
        "7.2d|rig import|rig import --diligent $IN/same/diligent --out $OUT/dir.toml"
    )
    local c fields
    for c in "${dir_cases[@]}"; do
        IFS='|' read -r -a fields <<< "$c"
        mkdir -p "$OUT/dir.png" "$OUT/dir.toml"
        # shellcheck disable=SC2086
        MAXSEC=1.5 hcase "${fields[0]}" D14 "${fields[1]} --out an existing folder" 2 "$OUT/dir." - - -- ${fields[2]}
    done
    read_only_and_unwritable
    hcase 7.5a D5 "synth --out its own exemplar" 2 "$IN/same/exemplar.png" - - -- \
        synth "$IN/same/exemplar.png" --size 64x64 --out "$IN/same/exemplar.png"
    hcase 7.5b D5 "render --out its own normal map" 2 "$IN/same/exemplar.png" - - -- \
        render "$IN/same/scene.toml" --out "$IN/same/exemplar.png"
    hcase 7.5c D5 "rig import --out its own light_directions.txt" 2 "light_directions.txt" - - -- \
        rig import --diligent "$IN/same/diligent" --out "$IN/same/diligent/light_directions.txt"
    hcase 7.6a D5 "capture --out its own photo folder" 2 "$IN/same/photos" - - -- \
        capture --rig "$IN/same/photos/rig.toml" --photos-from "$IN/same/photos" --out "$IN/same/photos"
    hcase 7.6b D5 "batch --out its own sessions folder" 2 "$IN/same/sessions" - - -- \
        batch "$IN/same/sessions" --out "$IN/same/sessions"
}

# A batch output folder is sound when it has no hidden file and every session folder in it holds
# the whole set; prints what is wrong, or nothing.
unsound_sets() {
    local dir=$1 s f
    find "$dir" -name '.*' | head -2
    for s in "$dir"/*/; do
        # batch-review/ holds the review page's previews, not a session.
        [ -d "$s" ] && [ "$(basename "$s")" != batch-review ] || continue
        for f in normal.exr normal.png albedo.png confidence.png report.json; do
            [ -f "$s$f" ] || { echo "$(basename "$s") lacks $f"; break; }
        done
    done
}

# 6.3 and 6.4: SIGINT (and SIGTERM) at random moments of a 40-session batch, then a re-run.
interrupts() {
    selected 6.3 || return 0
    local try signal delay rc bad start end note
    local dfl=(python3 -c 'import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execvp(sys.argv[1], sys.argv[1:])')
    # The moments are drawn within the batch's own length, timed once uninterrupted first: a
    # fixed range outlasts a batch on a fast machine, and the signal then finds nothing to stop.
    # Never before 0.3 s: until the wrapper has reset SIGINT, it is ignored as in any background
    # job of a script, and the batch would rightly run on.
    local t0 length
    rm -rf "$OUT/b40"
    t0=$(date +%s.%N)
    "$BIN" batch "$IN/batch40" --out "$OUT/b40" --quiet > /dev/null 2>&1
    length=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f", b - a }')
    for try in 1 2 3; do
        signal=INT
        [ "$try" = 3 ] && signal=TERM
        delay=$(awk -v s="$RANDOM" -v t="$length" 'BEGIN { srand(s); printf "%.2f", 0.3 + 0.7 * (t - 0.3) * rand() }')
        rm -rf "$OUT/b40"
        hash_inputs "$LOG/before"
        start=$(date +%s.%N)
        "${dfl[@]}" "$BIN" batch "$IN/batch40" --out "$OUT/b40" > "$LOG/stdout" 2> "$LOG/stderr" &
        local pid=$!
        sleep "$delay"
        kill -s "$signal" "$pid" 2> /dev/null
        wait "$pid"
        rc=$?
        end=$(date +%s.%N)
        hash_inputs "$LOG/after"
        bad=$(unsound_sets "$OUT/b40" | head -3 | tr '\n' ' ')
        note="SIG$signal after ${delay} s"
        local exit_ok=fail out_ok=pass temp_ok=pass inputs_ok=pass line_ok=-
        [ "$rc" = 130 ] && exit_ok=pass
        [ -n "$bad" ] && { out_ok=fail; note="$note; half sets: $bad"; }
        [ -n "$(hidden_files)" ] && { temp_ok=fail; note="$note; hidden: $(hidden_files | head -1)"; }
        [ -f "$OUT/b40/batch-report.json" ] || { out_ok=fail; note="$note; no batch-report.json"; }
        cmp -s "$LOG/before" "$LOG/after" || inputs_ok=fail
        record "6.3$try" D4 "SIG$signal during a 40-session batch" 130 "$rc" \
            "$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')" - "$exit_ok" "$line_ok" "$out_ok" \
            "$temp_ok" "$inputs_ok" - "$note"
    done
    # 6.4: the re-run into the interrupted folder completes every session and leaves no temp.
    slow 6.4 D4 "re-run into the interrupted folder" && { rm -rf "$OUT/b40"; return 0; }
    hash_inputs "$LOG/before"
    run_bin batch "$IN/batch40" --out "$OUT/b40"
    hash_inputs "$LOG/after"
    local count
    count=$(find "$OUT/b40" -name report.json | wc -l)
    bad=$(unsound_sets "$OUT/b40" | head -3 | tr '\n' ' ')
    local exit_ok=fail out_ok=pass temp_ok=pass inputs_ok=pass
    [ "$RC" = 0 ] && exit_ok=pass
    [ "$count" = 40 ] && [ -z "$bad" ] || out_ok=fail
    [ -n "$(hidden_files)" ] && temp_ok=fail
    cmp -s "$LOG/before" "$LOG/after" || inputs_ok=fail
    record 6.4 D4 "re-run into the interrupted folder" 0 "$RC" "$SECONDS_TAKEN" "$PEAK" "$exit_ok" - "$out_ok" \
        "$temp_ok" "$inputs_ok" - "$count of 40 sessions complete $bad $(head -1 "$LOG/stderr")"
    rm -rf "$OUT/b40"
}

# 6.5-6.7: a 2 MB tmpfs as the output (root only).
full_disk() {
    selected 6.5 || selected 6.6 || selected 6.7 || return 0
    local small=$SCRATCH/small
    mkdir -p "$small"
    if [ "$(id -u)" != 0 ] || ! mount -t tmpfs -o size=2m tmpfs "$small" 2> /dev/null; then
        skip 6.5 D3 "batch onto a full disk" "needs root to mount a tmpfs"
        skip 6.6 D3 "capture onto a full disk" "needs root to mount a tmpfs"
        skip 6.7 D3 "failed re-capture into a full folder" "needs root to mount a tmpfs"
        return
    fi
    MOUNTS+=("$small")
    MULTI=1 hcase 6.5 D3 "batch of 4 sessions onto a 2 MB tmpfs" 1 "No space left" "No space left" - -- \
        batch "$IN/batch4" --out "$small/maps"
    local bad
    bad=$(unsound_sets "$small/maps" 2> /dev/null | head -3 | tr '\n' ' ')
    local verdict=pass
    [ -n "$bad" ] && verdict=fail
    record 6.5b D3 "the batch's session folders on the full disk" - - - - - - "$verdict" - - - "${bad:-every set whole or absent}"
    rm -rf "${small:?}"/*
    # Fill the tmpfs to about 300 KB free.
    head -c $((2048 * 1024 - 300 * 1024)) /dev/zero > "$small/filler" 2> /dev/null
    hcase 6.6 D3 "capture onto a nearly full disk" 1 "No space left" "No space left" "$small/cap" -- \
        capture --rig "$RIG" --photos-from "$C" --out "$small/cap"
    rm -rf "${small:?}"/*
    # 6.7: the cheek captured whole, then the nose into the same folder with the disk full.
    run_bin capture --rig "$RIG" --photos-from "$C" --out "$small/cap"
    local before after
    before=$( (cd "$small/cap" && sha256sum ./*) 2> /dev/null)
    local free
    free=$(df --output=avail -k "$small" | tail -1)
    head -c $(( (free > 300 ? free - 300 : 0) * 1024 )) /dev/zero > "$small/filler" 2> /dev/null
    hcase 6.7 D3 "failed re-capture into the cheek's folder" 1 "No space left" "No space left" - -- \
        capture --rig "$IN/molds/nose/rig.toml" --photos-from "$IN/molds/nose" --out "$small/cap"
    after=$( (cd "$small/cap" && sha256sum ./*) 2> /dev/null)
    if [ "$before" = "$after" ]; then
        record 6.7b D3 "the cheek's set after the failed re-capture" - - - - - - pass - - - "unchanged"
    else
        record 6.7b D3 "the cheek's set after the failed re-capture" - - - - - - fail - - - \
            "changed: $(diff <(echo "$before") <(echo "$after") | grep -c '^>') files differ"
    fi
    rm -rf "${small:?}"/*
}

# 6.8: report.json already a folder in --out: the run fails and leaves the folder as it was.
report_is_a_folder() {
    selected 6.8 || return 0
    local dir=$SCRATCH/o68
    mkdir -p "$dir/report.json"
    hcase 6.8 D3 "capture: report.json in --out is a folder" 1 "report.json" - - -- \
        capture --rig "$RIG" --photos-from "$C" --out "$dir"
    local left
    left=$(cd "$dir" && find . -mindepth 1 | sort | tr '\n' ' ')
    local verdict=pass
    [ "$left" = "./report.json " ] || verdict=fail
    record 6.8b D3 "the folder after the failed capture" - - - - - - "$verdict" - - - "holds: $left"
    rm -rf "$dir"
}

# 7.3 and 7.4: --out on a read-only mount, and in a folder the user cannot write (uid 65534).
read_only_and_unwritable() {
    selected 7.3 || selected 7.4 || return 0
    local ro=$SCRATCH/ro
    mkdir -p "$ro"
    if [ "$(id -u)" = 0 ] && mount -t tmpfs -o ro,size=64k tmpfs "$ro" 2> /dev/null; then
        MOUNTS+=("$ro")
        hcase 7.3 D10 "synth --out on a read-only mount" 1 "$ro/s.png" "Read-only" - -- \
            synth "$IN/exemplars/truth.png" --size 32x32 --out "$ro/s.png"
    else
        skip 7.3 D10 "synth --out on a read-only mount" "needs root to mount a tmpfs"
    fi
    local locked=$SCRATCH/locked
    mkdir -p "$locked"
    chmod 755 "$locked"
    if [ "$(id -u)" = 0 ] && setpriv --reuid=65534 --regid=65534 --clear-groups test -x "$BIN" 2> /dev/null \
        && setpriv --reuid=65534 --regid=65534 --clear-groups test -r "$IN/exemplars/truth.png"; then
        RUN_AS=65534 hcase 7.4 D10 "synth --out in a folder without write permission" 1 "$locked/s.png" \
            "Permission denied" - -- synth "$IN/exemplars/truth.png" --size 32x32 --out "$locked/s.png"
    else
        skip 7.4 D10 "synth --out in a folder without write permission" "needs root and a binary uid 65534 can run"
    fi
}
