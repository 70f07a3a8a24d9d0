#!/usr/bin/env bash
# End-to-end checks of the latentpt command line: outputs exist, --resume continues, bad input
# fails with a message naming the file and a non-zero exit code (never a crash).
set -u
bin="$1"; src="$2"
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
fail=0; passed=0
check() { if "$@"; then passed=$((passed + 1)); else echo "FAILED: $*"; fail=$((fail + 1)); fi; }
expect_error() {  # expect_error NEEDLE cmd...: a non-zero exit that is not a signal, NEEDLE in stderr
    local needle="$1"; shift
    "$@" 2>"$out/err.txt" >/dev/null; local rc=$?
    if [ $rc -eq 0 ] || [ $rc -ge 128 ] || ! grep -q -- "$needle" "$out/err.txt"; then
        echo "FAILED: expected an error exit and '$needle' from: $* (rc=$rc)"; cat "$out/err.txt"; fail=$((fail + 1))
    else passed=$((passed + 1)); fi
}
scene="$src/scenes/cornell-box/scene.json"

"$bin" render "$scene" --spp 2 --res 24x16 --aov --aov-res 6x4 -q --out "$out/r.exr"
check test -s "$out/r.exr"; check test -s "$out/r.png"; check test -s "$out/r.normal.exr"
# Numbers that became others without a word: seed -1 was 2^64 - 1, exposure nan a black preview,
# 10^7 threads gigabytes; the RGB renderer's options did nothing with --edit.
expect_error "--seed: expected an integer" "$bin" render "$scene" --seed -1 --res 8x8 --spp 1 -q --out "$out/s.exr"
expect_error "--exposure: expected a finite number" "$bin" render "$scene" --exposure nan --res 8x8 --spp 1 -q --out "$out/s.exr"
expect_error "--threads" "$bin" --threads 10000000 render "$scene" --res 8x8 --spp 1 -q --out "$out/s.exr"
expect_error "excludes --aov" "$bin" render "$scene" --edit "$src/scenes/cornell-box/edits-demo.json" --aov -q --out "$out/s"
expect_error "--aov-res requires --aov" "$bin" render "$scene" --aov-res 4x4 --res 8x8 --spp 1 -q --out "$out/s.exr"
expect_error "a folder, not a --pairs file" "$bin" metrics --pairs "$out"
# The top-level options after the subcommand too ("not expected: 1 --threads" before).
"$bin" render "$scene" --res 8x8 --spp 1 -q --out "$out/t.exr" --threads 1 --sampler independent; check test -s "$out/t.exr"
expect_error "--vae-dir excludes --vae-encoder" "$bin" encode "$out/r.exr" --vae-dir "$out" --vae-encoder "$out/r.exr" -q --out "$out/z.exr"
# Options of another mode than the one chosen did nothing without a word.
expect_error "--target excludes --synthetic-res" "$bin" fit "$scene" --target "$out/r.exr" --synthetic-res 16x16 -q --out "$out/s_fit"
expect_error "--fit excludes --startup" "$bin" bench --fit --startup
expect_error "given twice to --test" "$bin" compare --test "$out/r.exr" "$out/r.exr" --ref "$out/r.exr"
expect_error "--define requires --scene" "$bin" compare --test "$out/r.exr" --ref "$out/r.exr" -D x=1
expect_error "--lr-min must be <= --lr" "$bin" fit "$scene" --lr-min 1 --lr 0.001 --synthetic-res 8x8 -q --out "$out/s_fit"
# Sizes beyond memory or a PNG's limit name their flag, before any work.
expect_error "--res: an image of 65536x65536 pixels needs" "$bin" render "$scene" --res 65536x65536 --spp 1 -q --out "$out/s.exr"
expect_error "--res: 1x1000001 is beyond the PNG preview" "$bin" render "$scene" --res 1x1000001 --spp 1 -q --out "$out/s.exr"
expect_error "--synthetic-res: an image of 65536x65536 pixels needs" "$bin" fit "$scene" --synthetic-res 65536x65536 --no-refiner -q --out "$out/s_fit"
check test ! -e "$out/s_fit"
# A rename onto a folder of the output's name failed and left the temporary beside it.
mkdir -p "$out/folder.exr"
expect_error "folder.exr: cannot write image" "$bin" render "$scene" --res 8x8 --spp 1 -q --out "$out/folder.exr"
check test -z "$(ls -A "$out" | grep '^\.folder\.tmp')"

# -D overrides a scene value as the dedicated flag does: the same pixels (render -D crashed from
# 2026-11-25 to 11-26: its option was bound to a local that was gone by parse time).
"$bin" render "$scene" --spp 2 --res 16x16 -q -D integrator.max_depth=2 --out "$out/define.exr"
"$bin" render "$scene" --spp 2 --res 16x16 -q --max-depth 2 --out "$out/flag.exr"
"$bin" render "$scene" --spp 2 --res 16x16 -q --out "$out/nodefine.exr"
check cmp -s "$out/define.exr" "$out/flag.exr"
check sh -c "! cmp -s '$out/define.exr' '$out/nodefine.exr'"
expect_error "key=value" "$bin" render "$scene" -q -D integrator.max_depth --out "$out/x.exr"
# A misspelt -D path, or a misspelt key in the file, changed nothing without a word.
expect_error "integrator.max_dept" "$bin" render "$scene" -q -D integrator.max_dept=2 --out "$out/x.exr"
# Options that only mean something beside another are refused alone (they did nothing).
expect_error "requires --edit" "$bin" render "$scene" -q --reference --out "$out/x.exr"
expect_error "requires --reference" "$bin" render "$scene" -q --ref-spp 8 --out "$out/x.exr"
expect_error "requires --edit" "$bin" render "$scene" -q --frames 0:1 --out "$out/x.exr"
expect_error "requires --encode" "$bin" fit "$scene" -q --ref-spp 8 --out "$out/x"
expect_error "requires --resume" "$bin" fit "$scene" -q --restart-if-changed --out "$out/x"
expect_error "requires --equal-noise" "$bin" bench --target-spp 8

# Equal-noise bench end to end at toy size against a 64-spp reference, and its missing-reference error.
"$bin" render "$scene" --spp 64 --res 16x16 -q --out "$out/noise_ref.exr"
check sh -c "'$bin' bench --equal-noise --scene '$scene' --reference '$out/noise_ref.exr' --res 16 --seeds 1 --target-spp 4 --json '$out/noise.json' 2>/dev/null | grep -q 'sobol: .* fewer spp'"
check grep -q '"sobol":\[\[4,' "$out/noise.json"
expect_error "TungstenRender.exr" "$bin" bench --equal-noise --scene "$scene"
small_refiner="--refiner-iterations 4 --refiner-expansion 1 --refiner-checkpoint-every 2"
"$bin" fit "$scene" --synthetic-res 8x8 --iterations 20 --spp 2 --final-spp 4 --checkpoint-every 10 -q -D integrator.max_depth=3 $small_refiner --out "$out/fit"
for f in params.json latent.exr latent_e.exr latent_a.exr latent_c.exr aov.exr loss.csv target.png render.png diff.png checkpoint/state.json \
         refiner.pt latent_refined.exr refiner_loss.csv metrics.json; do
    check test -s "$out/fit/$f"
done
check test "$(wc -l < "$out/fit/loss.csv")" -eq 21
check test "$(wc -l < "$out/fit/refiner_loss.csv")" -eq 5
# Stage 2 on its own continues from its checkpoint: its first rows, seconds included, stay.
head -5 "$out/fit/refiner_loss.csv" > "$out/refiner_loss_before.csv"
"$bin" refine "$out/fit" --iterations 6 --expansion 1 -q --resume
check test "$(wc -l < "$out/fit/refiner_loss.csv")" -eq 7
check cmp -s "$out/refiner_loss_before.csv" <(head -5 "$out/fit/refiner_loss.csv")
# A stage 1 that takes steps makes the refiner stale: without --refiner it is removed, not kept.
"$bin" fit "$scene" --synthetic-res 8x8 --iterations 30 --spp 2 --final-spp 4 -q -D integrator.max_depth=3 --out "$out/fit" --resume --no-refiner
check test "$(wc -l < "$out/fit/loss.csv")" -eq 31
check test ! -e "$out/fit/refiner.pt"
check test ! -e "$out/fit/refiner_checkpoint.pt"
expect_error "latent.exr" "$bin" refine "$out" -q
# A fit folder in use by another process (here util-linux flock holds its lock) is refused at once.
if command -v flock >/dev/null; then
    mkdir -p "$out/busy"
    flock "$out/busy/.latentpt.lock" sleep 120 &  # long enough on a loaded machine; killed below
    holder=$!
    sleep 0.5
    expect_error "in use by another latentpt process" "$bin" fit "$scene" --synthetic-res 8x8 --iterations 2 -q --no-refiner --out "$out/busy"
    expect_error "in use by another latentpt process" "$bin" refine "$out/busy" -q
    pkill -P $holder 2>/dev/null; kill $holder 2>/dev/null; wait $holder 2>/dev/null
fi

# An edit sequence split into frame ranges gives byte-identical files to one job (issue 20).
edits="$src/scenes/cornell-box/edits-demo.json"
"$bin" render "$out/fit" --edit "$edits" --spp 2 -q --out "$out/edit_all"
"$bin" render "$out/fit" --edit "$edits" --spp 2 -q --frames 0:2 --out "$out/edit_split"
"$bin" render "$out/fit" --edit "$edits" --spp 2 -q --frames 3:7 --out "$out/edit_split"
check diff -r "$out/edit_all" "$out/edit_split"
# --resume re-renders only frames without their frame_NNNN.done (a killed job's unfinished ones).
cp -r "$out/edit_all" "$out/edit_resume"
rm "$out/edit_resume"/frame_0005*
touch -d 2000-01-01 "$out/edit_resume/frame_0000.png"
"$bin" render "$out/fit" --edit "$edits" --spp 2 -q --resume --out "$out/edit_resume"
check test "$(stat -c %Y "$out/edit_resume/frame_0000.png")" = "$(date -d 2000-01-01 +%s)"
check test -f "$out/edit_resume/frame_0005.done"
check diff -r "$out/edit_all" "$out/edit_resume"
expect_error "not within the sequence" "$bin" render "$out/fit" --edit "$edits" --frames 3:9 -q --out "$out/x"
expect_error "A:B" "$bin" render "$out/fit" --edit "$edits" --frames 5 -q --out "$out/x"
# Every S-th frame (A:B:S, issue 16's frame subsets): exactly frames 0, 3, 6, the same files as
# the whole sequence's.
"$bin" render "$out/fit" --edit "$edits" --spp 2 -q --frames 0:7:3 --out "$out/edit_step"
check test "$(ls "$out/edit_step" | grep -c 'done$')" -eq 3
for i in 0000 0003 0006; do check cmp "$out/edit_all/frame_$i.png" "$out/edit_step/frame_$i.png"; done
expect_error "A:B:S" "$bin" render "$out/fit" --edit "$edits" --frames 0:7:0 -q --out "$out/x"
# A misspelt key in an edits file fails naming it (it used to render an unmoved camera).
printf '{"frames": 2, "camera": {"orbit": {"azimut": [0, 30]}}}' > "$out/typo-edits.json"
expect_error "camera.orbit.azimut" "$bin" render "$out/fit" --edit "$out/typo-edits.json" -q --out "$out/x"

expect_error "channels" "$bin" fit "$scene" --target "$out/r.exr" -q --out "$out/bad"
expect_error "does not exist" "$bin" render "$out/missing.json" -q --out "$out/x.exr"
printf '{"camera": {"fov": 40}, "shapes": [ {"type": "obj", "filename": "nope.obj", "material": "m"} ], "materials": {"m": {"type": "diffuse"}}}' > "$out/s.json"
expect_error "nope.obj" "$bin" render "$out/s.json" -q --out "$out/x.exr"
expect_error "WxH" "$bin" render "$scene" --res 12 -q --out "$out/x.exr"
# Out-of-range values are errors, not silently something else; a film too large fails with its size.
expect_error "must be >= 0, got -1" "$bin" render "$scene" --spp -1 -q --out "$out/x.exr"
expect_error "patience" "$bin" fit "$scene" --synthetic-res 8x8 --patience -1 -q --out "$out/x_fit"
expect_error "checkpoint-every" "$bin" fit "$scene" --synthetic-res 8x8 --checkpoint-every -1 -q --out "$out/x_fit"
expect_error "--threads: Value 0 not in range 1 to 4096" "$bin" --threads 0 render "$scene" -q --out "$out/x.exr"
expect_error "must be > 0" "$bin" fit "$scene" --iterations 0 -q --out "$out/bad"
expect_error "GiB" "$bin" render "$scene" --res 100000x100000 -q --out "$out/x.exr"
expect_error "--terms" "$bin" fit "$scene" --terms xyz -q --out "$out/bad"
expect_error "checkpoint" "$bin" fit "$scene" --resume -q --out "$out/never-fitted"

shared="${LATENTPT_SHARED:-$src/../shared}"
if [ -d "$shared/models/taesd3" ]; then
    "$bin" render "$scene" --spp 1 --res 20x12 -q --out "$out/odd.exr"
    expect_error "not a multiple of 8" "$bin" encode "$out/odd.png" -q --out "$out/bad.exr"
    "$bin" render "$scene" --spp 2 --res 32x16 -q --out "$out/e.exr"
    "$bin" encode "$out/e.png" -q --out "$out/lat.exr"; check test -s "$out/lat.exr"
    check test "$("$bin" decode "$out/lat.exr" -q --out "$out/dec.png" && oiiotool --info "$out/dec.png" | grep -c '32 x   16')" -eq 1
    "$bin" viz "$out/lat.exr" -q --out "$out/viz.png"; check test -s "$out/viz.png"
    # Readers tell a picture's kind by its name: PNG bytes in "v.exr" read as linear; a decode
    # over its input replaced the latent; a latent's first three channels were encoded as RGB.
    expect_error "must end in .png" "$bin" viz "$out/lat.exr" -q --out "$out/viz.exr"
    expect_error "must end in .png or .exr" "$bin" decode "$out/lat.exr" -q --out "$out/dec.jpg"
    expect_error "is the input file" "$bin" decode "$out/lat.exr" -q --out "$out/lat.exr"
    expect_error "needs 3 channels (RGB) or 4" "$bin" encode "$out/lat.exr" -q --out "$out/lat2.exr"
    "$bin" decode "$out/lat.exr" -q --out "$out/dec_upper.EXR"; check oiiotool --info "$out/dec_upper.EXR"
    # metrics --pairs: one JSON line per pair (empty lines skipped), each what a call of its own
    # prints; an image against itself scores 0, LPIPS too (24² is above LPIPS's smallest size).
    "$bin" render "$scene" --spp 1 --res 24x24 -q --out "$out/m1.exr"
    "$bin" render "$scene" --spp 1 --res 24x24 --seed 2 -q --out "$out/m2.exr"
    printf '%s\t%s\n\n%s\t%s\n' "$out/m1.png" "$out/m2.png" "$out/m2.png" "$out/m2.png" > "$out/pairs.txt"
    "$bin" metrics --pairs "$out/pairs.txt" > "$out/pairs.jsonl"
    "$bin" metrics "$out/m1.png" "$out/m2.png" --json > "$out/one.json"
    check test "$(wc -l < "$out/pairs.jsonl")" -eq 2
    check sh -c "head -1 '$out/pairs.jsonl' | cmp -s - '$out/one.json'"
    check sh -c "! grep -q '\"lpips\": null' '$out/one.json'"
    check sh -c "sed -n 2p '$out/pairs.jsonl' | grep -q '\"mse\": 0,.*\"lpips\": 0}'"
    printf '%s %s\n' "$out/m1.png" "$out/m2.png" > "$out/bad_pairs.txt"
    expect_error "bad_pairs.txt:1: expected two paths separated by one tab" "$bin" metrics --pairs "$out/bad_pairs.txt"
    printf '%s\t%s\n' "$out/m1.png" "$out/nope.png" > "$out/bad_pairs.txt"
    expect_error "nope.png not found" "$bin" metrics --pairs "$out/bad_pairs.txt"
    expect_error "excludes" "$bin" metrics "$out/m1.png" "$out/m2.png" --pairs "$out/pairs.txt"
    # A NaN in an image is an error naming it: metrics said "MSE nan ... PSNR inf (identical)",
    # encode wrote NaN latents, decode a black picture.
    oiiotool --pattern constant:color=nan,0.5,0.5 16x16 3 -d float -o "$out/nan.exr"
    oiiotool --pattern constant:color=0.5,0.5,0.5 16x16 3 -d float -o "$out/half.exr"
    expect_error "nan.exr: value at pixel (0, 0), channel 0 is not finite" "$bin" metrics "$out/nan.exr" "$out/half.exr"
    expect_error "nan.exr: value at pixel (0, 0), channel 0 is not finite" "$bin" encode "$out/nan.exr" -q --out "$out/nan_latent.exr"
    oiiotool --pattern constant:color=0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,nan 2x2 16 -d float -o "$out/nan16.exr"
    expect_error "nan16.exr: value at pixel (0, 0), channel" "$bin" decode "$out/nan16.exr" -q --out "$out/nan.png"
    expect_error "nan16.exr: value at pixel (0, 0), channel" "$bin" viz "$out/nan16.exr" -q --out "$out/nan.png"
    expect_error "expected an RGB image, found 16" "$bin" compare --test "$out/nan16.exr" --ref "$out/nan16.exr"
    # Resolutions and frame ranges are whole integers in range: sscanf read '4294967304x8' as 8x8.
    expect_error "--res expects WxH" "$bin" render "$scene" --res 4294967304x8 --spp 1 -q --out "$out/wrap.exr"
    expect_error "--res expects WxH" "$bin" render "$scene" --res 8x8junk --spp 1 -q --out "$out/wrap.exr"
    # Sizes beyond the machine's memory are refused before any work, naming where they come from.
    expect_error "--aov-res: an image of 100000x100000 pixels needs" "$bin" render "$scene" --aov --aov-res 100000x100000 --res 8x8 --spp 1 -q --out "$out/huge.exr"
    # The TorchScript VAE path from the command line: TAESD3 exported by our script encodes alike.
    py=/usr/bin/python3; [ -x "$py" ] || py=python3
    if "$py" -c 'import torch' 2>/dev/null && "$py" "$src/tools/export_taesd3.py" --weights "$shared/models/taesd3" --out "$out/ts" >/dev/null; then
        "$bin" encode "$out/e.png" -q --vae-encoder "$out/ts/encoder.pt" --vae-decoder "$out/ts/decoder.pt" --vae-config "$out/ts/vae.json" --out "$out/lat_ts.exr"
        check oiiotool "$out/lat_ts.exr" "$out/lat.exr" --fail 1e-4 --diff
        expect_error "all of --vae-encoder" "$bin" encode "$out/e.png" -q --vae-encoder "$out/ts/encoder.pt" --out "$out/x.exr"
    else
        echo "skipping TorchScript VAE checks: no python3 with torch (python3-torch)"
    fi
    expect_error "channels" "$bin" decode "$out/r.exr" -q --out "$out/x.png"
    "$bin" fit "$scene" --encode --encode-res 16x16 --ref-spp 4 --iterations 3 --spp 1 --final-spp 2 -q $small_refiner --out "$out/enc"
    for f in reference.png reference_rgb.exr target.exr target_decoded.png decoded.png decoded_refined.png metrics.json; do check test -s "$out/enc/$f"; done
    check grep -q vae_roundtrip "$out/enc/metrics.json"
    # EXRs of display values (the fit's reference, a decoded latent) say so in their header, and
    # metrics and encode read them as such: against their PNGs they differ by 8-bit rounding
    # only (read as linear, they would be display-mapped twice). A render's linear EXR encodes
    # as fit maps its reference: the render fit traced (its seed 0x5eed = 24301) encodes to
    # fit's target.exr exactly.
    check sh -c "'$bin' metrics '$out/enc/reference_rgb.exr' '$out/enc/reference.png' | grep -q 'display RGB (EXR marked so)'"
    check sh -c "'$bin' metrics --json '$out/enc/reference_rgb.exr' '$out/enc/reference.png' | python3 -c 'import json,sys; assert json.load(sys.stdin)[\"mse\"] < 4e-6'"
    "$bin" decode "$out/enc/target.exr" -q --out "$out/enc_dec.exr"
    check sh -c "'$bin' metrics --json '$out/enc_dec.exr' '$out/enc/target_decoded.png' | python3 -c 'import json,sys; assert json.load(sys.stdin)[\"mse\"] < 4e-6'"
    "$bin" render "$scene" --res 16x16 --spp 4 --seed 24301 -q --out "$out/enc_ref.exr"
    "$bin" encode "$out/enc_ref.exr" -q --out "$out/enc_ref_latent.exr"
    check oiiotool "$out/enc_ref_latent.exr" "$out/enc/target.exr" --fail 1e-6 --diff
    expect_error "holds display values" "$bin" compare --test "$out/enc_ref.exr" --ref "$out/enc/reference_rgb.exr"
    # Augmented views from the fit's own reference: trained, recorded; a bad name is refused.
    cp -r "$out/enc" "$out/enc_aug"
    "$bin" refine "$out/enc_aug" --iterations 6 --expansion 1 -q --augment dihedral
    check grep -q '"augment": "dihedral"' "$out/enc_aug/metrics.json"
    "$bin" refine "$out/enc_aug" --iterations 6 --expansion 1 -q --augment shift --latent-target compensated
    check grep -q '"augment": "shift"' "$out/enc_aug/metrics.json"
    expect_error "augment" "$bin" refine "$out/enc_aug" -q --augment flip
    # The compensated latent target: trained, recorded; refused without the fit's RGB reference.
    cp -r "$out/enc" "$out/enc_comp"
    "$bin" refine "$out/enc_comp" --iterations 6 --expansion 1 -q --latent-target compensated
    check grep -q '"latent_target": "compensated"' "$out/enc_comp/metrics.json"
    expect_error "latent-target" "$bin" refine "$out/enc_comp" -q --latent-target decoded
    # ... its bias averaged over coarser blocks: recorded; refused where the blocks do not tile
    # the reference or the target is not compensated.
    "$bin" refine "$out/enc_comp" --iterations 6 --expansion 1 -q --latent-target compensated --latent-target-block 16
    check grep -q '"latent_target_block": 16' "$out/enc_comp/metrics.json"
    expect_error "latent-target-block) 24 does not divide the 16x16 reference" "$bin" refine "$out/enc_comp" -q --iterations 2 --latent-target compensated --latent-target-block 24
    expect_error "latent-target-block (fit --refiner-latent-target-block) must be 0 unless" "$bin" refine "$out/enc_comp" -q --iterations 2 --latent-target-block 8
    expect_error "window-stride (fit --refiner-window-stride) must be at most --crop" "$bin" refine "$out/enc_comp" -q --iterations 2 --crop 8 --window-stride 9
    expect_error "input-noise (fit --refiner-input-noise) must be 0 with --inputs terms" "$bin" refine "$out/enc_comp" -q --iterations 2 --input-noise 0.1 --inputs terms
    rm "$out/enc_comp/reference_rgb.exr"
    expect_error "reference_rgb.exr: refine --latent-target compensated" "$bin" refine "$out/enc_comp" -q --iterations 2 --latent-target compensated
    # Fits sharing a training reference through --reference-cache: traced once, the same target
    # as a fit that traces its own.
    for d in encc1 encc2; do
        "$bin" fit "$scene" --encode --encode-res 16x16 --ref-spp 4 --iterations 3 --spp 1 --final-spp 2 -q --no-refiner --reference-cache "$out/trefs" --out "$out/$d"
    done
    check test "$(ls "$out/trefs" | wc -l)" -eq 2
    check cmp "$out/enc/target.exr" "$out/encc1/target.exr"
    check cmp "$out/enc/target.exr" "$out/encc2/target.exr"
    check cmp "$out/enc/reference_rgb.exr" "$out/encc2/reference_rgb.exr"
    # An unedited frame is the training view: its reference is the fits' (same cache key), not a new trace.
    printf '{"frames": 2, "shapes": [{"id": "light", "translate": [[0,0,0],[0.5,0,0]]}]}' > "$out/move0.json"
    "$bin" render "$out/encc1" --edit "$out/move0.json" --reference --ref-spp 4 --spp 2 -q --reference-cache "$out/trefs" --out "$out/edt"
    check test "$(ls "$out/trefs" | grep -c frame_0000)" -eq 0
    check test "$(ls "$out/trefs" | grep -c frame_0001)" -eq 2
    check cmp "$out/encc1/reference.png" "$out/edt/frame_0000_reference.png"
    # An identity edit reproduces the fit's final latent and refined latent exactly (same seed and spp).
    printf '{"frames": 1}' > "$out/identity.json"
    "$bin" render "$out/enc" --edit "$out/identity.json" --seed 1 --spp 2 -q --out "$out/ed"
    expect_error "--frames expects A:B" "$bin" render "$out/enc" --edit "$out/identity.json" --frames 0:4294967297 -q --out "$out/ed_wrap"
    mkdir -p "$out/enc_huge" && cp "$out/enc/fit.json" "$out/enc/params.json" "$out/enc_huge/"
    sed -i 's/"latent_width": [0-9]*/"latent_width": 100000/; s/"latent_height": [0-9]*/"latent_height": 100000/' "$out/enc_huge/fit.json"
    expect_error "fit.json: latent_width x latent_height: an image of" timeout 60 "$bin" render "$out/enc_huge" --edit "$out/identity.json" -q --out "$out/ed_huge"
    check oiiotool "$out/ed/frame_0000_latent.exr" "$out/enc/latent.exr" --fail 0 --failpercent 0 --diff
    check oiiotool "$out/ed/frame_0000_refined.exr" "$out/enc/latent_refined.exr" --fail 0 --failpercent 0 --diff
    check test -s "$out/ed/frame_0000.png"; check test -s "$out/ed/frame_0000_rendered.png"
    # The same frame rendered again into that folder by a fit without a refiner: the refined
    # latent, its AOVs and the unrefined picture of the earlier run do not stay beside it.
    cp -r "$out/enc" "$out/enc_noref" && rm "$out/enc_noref/refiner.pt"
    cp -r "$out/ed" "$out/ed_noref"
    "$bin" render "$out/enc_noref" --edit "$out/identity.json" --seed 1 --spp 2 -q --out "$out/ed_noref"
    check test -s "$out/ed_noref/frame_0000.png"
    for f in frame_0000_refined.exr frame_0000_aov.exr frame_0000_rendered.png; do check test ! -e "$out/ed_noref/$f"; done
    # A refiner reading the transport terms (--inputs terms): an identity edit renders them exactly
    # as the fit wrote them (latent_e/a/c.exr), so it reproduces the refined latent too.
    cp -r "$out/enc" "$out/enc_terms"
    "$bin" refine "$out/enc_terms" --iterations 4 --expansion 1 -q --inputs terms
    check grep -q '"inputs": "terms"' "$out/enc_terms/metrics.json"
    "$bin" render "$out/enc_terms" --edit "$out/identity.json" --seed 1 --spp 2 -q --out "$out/ed_terms"
    check oiiotool "$out/ed_terms/frame_0000_refined.exr" "$out/enc_terms/latent_refined.exr" --fail 0 --failpercent 0 --diff
    check sh -c "! cmp -s '$out/ed_terms/frame_0000_refined.exr' '$out/ed/frame_0000_refined.exr'"
    expect_error "--inputs" "$bin" refine "$out/enc_terms" --iterations 4 --expansion 1 -q --resume
    rm "$out/enc_terms/latent_c.exr"
    expect_error "latent_c.exr" "$bin" refine "$out/enc_terms" --iterations 4 --expansion 1 -q --inputs terms
    # Emitter cells (--emitter-cells): refine traces them from the fit's scene and an identity edit
    # traces the same grid, so it reproduces the refined latent; resuming without them is refused.
    cp -r "$out/enc" "$out/enc_cells"
    "$bin" refine "$out/enc_cells" --iterations 4 --expansion 1 -q --emitter-cells 2
    check grep -q '"emitter_cells": 2' "$out/enc_cells/metrics.json"
    "$bin" render "$out/enc_cells" --edit "$out/identity.json" --seed 1 --spp 2 -q --out "$out/ed_cells"
    check oiiotool "$out/ed_cells/frame_0000_refined.exr" "$out/enc_cells/latent_refined.exr" --fail 0 --failpercent 0 --diff
    check sh -c "! cmp -s '$out/ed_cells/frame_0000_refined.exr' '$out/ed/frame_0000_refined.exr'"
    expect_error "--emitter-cells" "$bin" refine "$out/enc_cells" --iterations 4 --expansion 1 -q --resume
    expect_error "emitter-cells (fit --refiner-emitter-cells) must be 0 with --augment mirror" "$bin" refine "$out/enc_cells" -q --iterations 2 --emitter-cells 2 --augment mirror
    # The emitter refiner (--emitters): trained beside refiner.pt, the training view's refined
    # latent unchanged; an identity edit is the main refiner's alone, a frame whose light moved
    # takes its output there; refused without refiner.pt.
    cp -r "$out/enc" "$out/enc_emit"
    "$bin" refine "$out/enc_emit" --emitters --iterations 4 --expansion 1 -q --augment shift
    check test -s "$out/enc_emit/refiner_emitters.pt"
    check grep -q '"emitter_refiner"' "$out/enc_emit/metrics.json"
    check cmp "$out/enc_emit/latent_refined.exr" "$out/enc/latent_refined.exr"
    "$bin" render "$out/enc_emit" --edit "$out/identity.json" --seed 1 --spp 2 -q --out "$out/ed_emit"
    check oiiotool "$out/ed_emit/frame_0000_refined.exr" "$out/ed/frame_0000_refined.exr" --fail 0 --failpercent 0 --diff
    for d in enc enc_emit; do
        "$bin" render "$out/$d" --edit "$out/move0.json" --frames 1:1 --spp 2 -q --out "$out/mv_$d"
    done
    check oiiotool "$out/mv_enc/frame_0001_latent.exr" "$out/mv_enc_emit/frame_0001_latent.exr" --fail 0 --failpercent 0 --diff
    check sh -c "! cmp -s '$out/mv_enc/frame_0001_refined.exr' '$out/mv_enc_emit/frame_0001_refined.exr'"
    rm "$out/enc_emit/refiner.pt"
    expect_error "refiner.pt: not found" "$bin" refine "$out/enc_emit" --emitters --iterations 2 -q
    expect_error "without refiner.pt" "$bin" render "$out/enc_emit" --edit "$out/identity.json" -q --out "$out/ed_emit2"
    # Another latent resolution than training: the refiner is fully convolutional.
    "$bin" render "$out/enc" --edit "$out/identity.json" --res 4x3 --spp 2 -q --out "$out/ed_res"
    check test "$(oiiotool --info "$out/ed_res/frame_0000_refined.exr" | grep -c ' 4 x  *3,')" -eq 1
    check test "$(oiiotool --info "$out/ed_res/frame_0000.png" | grep -c '32 x  *24,')" -eq 1
    printf '{"frames": 2, "shapes": [{"id": "light", "translate": [[0,0,0],[0.5,0,0]]}]}' > "$out/move.json"
    "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --out "$out/ed2"
    check test "$(wc -l < "$out/ed2/metrics.csv")" -eq 3
    check test "$(ls "$out/refs" | wc -l)" -eq 4  # display RGB and its encoding per frame
    # From the cache: the same references, so the same metrics.
    "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --out "$out/ed2c"
    check cmp "$out/ed2/metrics.csv" "$out/ed2c/metrics.csv"
    # Scores made without LPIPS weights leave rgb_lpips empty; with the weights back, --resume
    # scores those frames again rather than keep the empty cells (which means would skip).
    mkdir -p "$out/nolpips/models" && ln -sfn "$shared/models/taesd3" "$out/nolpips/models/taesd3"
    lpips_cells() { awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "rgb_lpips") c = i; next } { print $c }' "$1"; }
    LATENTPT_SHARED="$out/nolpips" "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 --res 3x3 -q --out "$out/ed_lp"
    check test "$(lpips_cells "$out/ed_lp/metrics.csv" | grep -c .)" -eq 0
    if [ -f "$shared/models/lpips/lpips_squeeze_v0.1.safetensors" ]; then
        "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 --res 3x3 -q --resume --out "$out/ed_lp"
        check test "$(lpips_cells "$out/ed_lp/metrics.csv" | grep -c '^[0-9]')" -eq 2
    fi
    # A cache written before EXRs carried the display mark: read as before and marked in place.
    f1="$out/refs/move_16x16_2spp_clip_frame_0001_own_seed.exr"
    cp "$f1" "$out/marked.exr"
    oiiotool "$out/marked.exr" --eraseattrib "latentpt:values" -o "$f1"
    check sh -c "! oiiotool --info -v '$f1' | grep -q '^ *latentpt:values: '"  # oiiotool's history names it
    "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --out "$out/ed2u"
    check cmp "$out/ed2/metrics.csv" "$out/ed2u/metrics.csv"
    check sh -c "oiiotool --info -v '$f1' | grep -q '^ *latentpt:values: \"display\"'"
    check cmp "$out/marked.exr" "$f1"
    # Cached references record what they show (scene text, -D, edit file and frame): another
    # sequence of the same name, or another scene in the same folder, is refused, naming the
    # file; a cache from before the record is read as before and given it in place.
    check sh -c "oiiotool --info -v '$f1' | grep -q '^ *latentpt:source: \"fnv1a64:'"
    mkdir -p "$out/other"
    printf '{"frames": 2, "shapes": [{"id": "light", "translate": [[0,0,0],[0.2,0,0]]}]}' > "$out/other/move.json"
    expect_error "move_16x16_2spp_clip_frame_0001_own_seed.exr: a cached reference of another scene" "$bin" render "$out/enc" --edit "$out/other/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --out "$out/ed2o"
    sed 's/"reflectance": \[0.63, 0.065, 0.05\]/"reflectance": [0.05, 0.065, 0.63]/' "$scene" > "$out/other/scene.json"
    check sh -c "! cmp -s '$scene' '$out/other/scene.json'"
    expect_error "training_16x16_4spp_clip.exr: a cached reference of another scene" "$bin" fit "$out/other/scene.json" --encode --encode-res 16x16 --ref-spp 4 --iterations 3 --spp 1 --final-spp 2 -q --no-refiner --reference-cache "$out/trefs" --out "$out/encc3"
    # A cached latent another VAE encoded (its record says so) is encoded again, not taken.
    l1="$out/refs/move_16x16_2spp_clip_frame_0001_own_seed_latent.exr"
    check sh -c "oiiotool --info -v '$l1' | grep -q '^ *latentpt:source: \"fnv1a64:.* encoded by fnv1a64:'"
    cp "$l1" "$out/latent_before.exr"
    oiiotool "$l1" --attrib "latentpt:source" "another VAE" -o "$l1"
    "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --out "$out/ed2v"
    check cmp "$out/ed2/metrics.csv" "$out/ed2v/metrics.csv"
    check sh -c "oiiotool --info -v '$l1' | grep -q '^ *latentpt:source: \"fnv1a64:.* encoded by fnv1a64:'"
    check oiiotool "$l1" "$out/latent_before.exr" --fail 0 --failpercent 0 --diff
    oiiotool "$out/marked.exr" --eraseattrib "latentpt:source" -o "$f1"
    check sh -c "! oiiotool --info -v '$f1' | grep -q '^ *latentpt:source: '"
    "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --out "$out/ed2s"
    check cmp "$out/ed2/metrics.csv" "$out/ed2s/metrics.csv"
    check cmp "$out/marked.exr" "$f1"
    # Another --ref-seed: independent references of the same frames under their own cache names
    # (the edited frame's and the training view's), the default seed's files untouched.
    cp -r "$out/refs" "$out/refs_before"
    "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --ref-seed 7 --out "$out/ed2r"
    check test "$(ls "$out/refs" | grep -c _seed7)" -eq 4
    check test -s "$out/refs/training_16x16_2spp_clip_seed7.exr"
    for f in "$out/refs_before"/*; do check cmp "$f" "$out/refs/$(basename "$f")"; done
    check sh -c "! cmp -s '$out/refs/move_16x16_2spp_clip_frame_0001_own_seed.exr' '$out/refs/move_16x16_2spp_clip_frame_0001_own_seed_seed7.exr'"
    check sh -c "! cmp -s '$out/ed2/metrics.csv' '$out/ed2r/metrics.csv'"
    # Each edited frame's reference has its own seed: three frames of one edited scene (the light
    # moved by a constant) get different traces; one seed for all would give the same bytes.
    printf '{"frames": 3, "shapes": [{"id": "light", "translate": [[0.5,0,0]]}]}' > "$out/hold.json"
    "$bin" render "$out/enc" --edit "$out/hold.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/hrefs" --out "$out/edh"
    check test -s "$out/hrefs/hold_16x16_2spp_clip_frame_0002_own_seed.exr"
    check sh -c "! cmp -s '$out/hrefs/hold_16x16_2spp_clip_frame_0001_own_seed.exr' '$out/hrefs/hold_16x16_2spp_clip_frame_0002_own_seed.exr'"
    check sh -c "! cmp -s '$out/hrefs/hold_16x16_2spp_clip_frame_0000_own_seed.exr' '$out/hrefs/hold_16x16_2spp_clip_frame_0002_own_seed.exr'"
    # The workflow's chunk jobs (frames 0:0 and 1:1, each writing metrics_A-B.csv) merged by
    # experiment_lib.merge_metrics: byte for byte the one job's metrics.csv (issue 20).
    for r in 0:0 1:1; do
        "$bin" render "$out/enc" --edit "$out/move.json" --reference --ref-spp 2 --spp 2 -q --reference-cache "$out/refs" --frames $r --out "$out/ed2s"
    done
    python3 -c "import sys; sys.path.insert(0, '$src/scripts'); import experiment_lib as X; X.merge_metrics(['$out/ed2s/metrics_0-0.csv', '$out/ed2s/metrics_1-1.csv'], '$out/ed2s/metrics.csv')"
    check cmp "$out/ed2/metrics.csv" "$out/ed2s/metrics.csv"
    check grep -q "latent_dssim,rgb_mse_x100" "$out/ed2/metrics.csv"
    check grep -q "rgb_ssim,rgb_lpips,refined_latent_mse" "$out/ed2/metrics.csv"
    check sh -c "'$bin' bench --equal-error '$out/enc' --max-spp 16 | grep -q 'latent space, MSE'"
    expect_error "reference_rgb.exr" "$bin" bench --equal-error "$out/fit"
    printf '{"shapes": [{"id": "nope"}]}' > "$out/bad.json"
    expect_error "nope" "$bin" render "$out/enc" --edit "$out/bad.json" -q --out "$out/ed3"
    expect_error "fit.json" "$bin" render "$out" --edit "$out/identity.json" -q --out "$out/ed4"
else
    echo "skipping VAE command checks: $shared/models/taesd3 not found (set LATENTPT_SHARED)"
fi

echo "$passed passed, $fail failed"
[ $fail -eq 0 ]
