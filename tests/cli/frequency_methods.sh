#!/usr/bin/env bash
# idrig identify --method levy-sk | stable-nls | pole-residue | mbk on FRF tables written here
# with awk (exact FRFs of known systems) and on a time record (FRF estimated first).
set -euo pipefail
idrig=$1
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT
# Seed 001's plant W(p) = (0.5p + 1)/(p^3 + 2.5p^2 + 4p + 1.5) on 200 log-spaced lines.
awk 'BEGIN { print "f_hz,re,im"; pi = 3.141592653589793
  for (k = 1; k <= 200; k++) { f = 0.01 * exp(log(300) * (k - 1) / 199); w = 2 * pi * f
    nr = 1; ni = 0.5 * w; dr = 1.5 - 2.5 * w * w; di = 4 * w - w * w * w; d = dr * dr + di * di
    printf "%.17g,%.17g,%.17g\n", f, (nr * dr + ni * di) / d, (ni * dr - nr * di) / d } }' > "$dir/plant.csv"
"$idrig" identify --method levy-sk --data "$dir/plant.csv" --order 3 --option numerator_degree=1 > "$dir/levy.txt"
grep -q "den: 1 2.5 4 1.5" "$dir/levy.txt"
grep -q "num: 0.5 1" "$dir/levy.txt"
"$idrig" identify --method levy-sk --data "$dir/plant.csv" --order 3 --option numerator_degree=1 --json > "$dir/levy.json"
grep -q '"format": "idrig.model/1"' "$dir/levy.json"
grep -q '"method": "levy-sk"' "$dir/levy.json"
"$idrig" identify --method stable-nls --data "$dir/plant.csv" --order 3 --option numerator_degree=1 --json > "$dir/nls.json"
grep -q '"status": "ok"' "$dir/nls.json"
grep -q '"stable": true' "$dir/nls.json"
# The JSON model is usable by simulate.
"$idrig" example --out "$dir/rec.csv" --samples 200 --noise 0
"$idrig" simulate --model "$dir/nls.json" --data "$dir/rec.csv" --out "$dir/sim.csv"

# Two lightly damped modes, ω_n = 10 and 25 rad/s, ζ = 0.02: receptance Σ 1/(ω_n² − ω² + 2iζω_nω).
awk 'BEGIN { print "f_hz,re,im"; pi = 3.141592653589793
  for (k = 0; k < 400; k++) { w = 5 + 30 * k / 399; re = 0; im = 0
    split("10 25", wn, " ")
    for (m = 1; m <= 2; m++) { dr = wn[m] * wn[m] - w * w; di = 2 * 0.02 * wn[m] * w; d = dr * dr + di * di
      re += dr / d; im -= di / d }
    printf "%.17g,%.17g,%.17g\n", w / (2 * pi), re, im } }' > "$dir/modes.csv"
"$idrig" identify --method pole-residue --data "$dir/modes.csv" > "$dir/modes.txt"
cat "$dir/modes.txt"
# Rows: k, Re s, Im s, f_n, zeta, Q. Expect s = −0.2 ± 9.998i and −0.5 ± 24.995i.
awk '$1 ~ /^[0-9]+$/ && NF >= 6 { if ($2 > -0.2001 && $2 < -0.1999 && $3 > 9.9979 && $3 < 9.9981) a = 1
  if ($2 > -0.5001 && $2 < -0.4999 && $3 > 24.9949 && $3 < 24.9951) b = 1 }
  END { exit (a && b ? 0 : 1) }' "$dir/modes.txt"
"$idrig" identify --method pole-residue --data "$dir/modes.csv" --json | grep -q '"damping_ratio"'
# Noise relative to |H| (1 %, awk's rand with a fixed seed): weights 1/|H|; every mode comes
# with standard errors, and they cover the truth (|error| < 4 std) for the two real modes.
awk -F, 'BEGIN { srand(7) } NR == 1 { print; next }
  { m = sqrt($2 * $2 + $3 * $3); u1 = rand(); u2 = rand(); r = sqrt(-2 * log(u1 + 1e-300)) * 0.01 * m / sqrt(2)
    printf "%s,%.17g,%.17g\n", $1, $2 + r * cos(6.283185307179586 * u2), $3 + r * sin(6.283185307179586 * u2) }' \
  "$dir/modes.csv" > "$dir/noisy.csv"
"$idrig" identify --method pole-residue --data "$dir/noisy.csv" --option weight=inverse_magnitude --json > "$dir/noisy.json"
jq -e '[.identification.details.modes[] | select(.fictitious | not)] | length == 2' "$dir/noisy.json" > /dev/null
jq -e '[.identification.details.modes[] | select(.fictitious | not) | .std.real > 0 and .std.imag > 0 and .std.damping_ratio > 0] | all' \
  "$dir/noisy.json" > /dev/null
jq -e '[.identification.details.modes[] | select(.fictitious | not)
        | (.eigenvalue[0] - (if .eigenvalue[1] < 15 then -0.2 else -0.5 end)) / .std.real | fabs < 4] | all' \
  "$dir/noisy.json" > /dev/null
"$idrig" identify --method pole-residue --data "$dir/noisy.csv" --option max_residual_poles=0 | grep -q "4 poles (2 peaks + 2 fictitious)"

# 2-DOF receptance matrix: M = diag(1, 2), K = [30 -10; -10 20], B = 0.01 K.
awk 'BEGIN { print "f_hz,re_1_1,im_1_1,re_2_1,im_2_1,re_1_2,im_1_2,re_2_2,im_2_2"; pi = 3.141592653589793
  for (k = 1; k <= 100; k++) { w = 0.1 * k
    ar = 30 - w * w; ai = 0.3 * w; br = -10; bi = -0.1 * w; cr = br; ci = bi; dr = 20 - 2 * w * w; di = 0.2 * w
    # det = a d − b c; G = [d −b; −c a]/det
    detr = ar * dr - ai * di - (br * cr - bi * ci); deti = ar * di + ai * dr - (br * ci + bi * cr); n = detr * detr + deti * deti
    g11r = (dr * detr + di * deti) / n; g11i = (di * detr - dr * deti) / n
    g12r = (-br * detr - bi * deti) / n; g12i = (-bi * detr + br * deti) / n
    g22r = (ar * detr + ai * deti) / n; g22i = (ai * detr - ar * deti) / n
    printf "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", w / (2 * pi), g11r, g11i, g12r, g12i, g12r, g12i, g22r, g22i } }' > "$dir/mbk.csv"
for variant in product difference; do
  "$idrig" identify --method mbk --data "$dir/mbk.csv" --option variant=$variant --json > "$dir/mbk.json"
  tr -d ' \n' < "$dir/mbk.json" | grep -Eq '"K":\[\[(29\.9999999|30\.0000000)[0-9]*,-(9\.9999999|10\.000000)[0-9]*\]'
done

# A time record: the FRF is estimated first (H1/Welch), then fitted.
"$idrig" example --out "$dir/long.csv" --samples 8192 --noise 0
"$idrig" identify --method levy-sk --data "$dir/long.csv" --order 3 --option numerator_degree=1 \
  --option segment_length=1024 --option f_max_hz=0.5 --json > "$dir/time.json"
grep -q '"frf_source": "welch"' "$dir/time.json"

# Bad input: exit code 2 and a message naming the problem.
printf 'f_hz,re,im\n1,1,0\n2,nan,0\n' > "$dir/nan.csv"
set +e
out=$("$idrig" identify --method levy-sk --data "$dir/nan.csv" --order 1 2>&1); rc=$?
set -e
[ $rc -eq 2 ] && grep -q "NaN" <<<"$out"
set +e
out=$("$idrig" identify --method levy-sk --data "$dir/plant.csv" 2>&1); rc=$?
set -e
[ $rc -eq 2 ] && grep -q "needs --order" <<<"$out"
set +e
out=$("$idrig" identify --method mbk --data "$dir/plant.csv" --option variant=sum 2>&1); rc=$?
set -e
[ $rc -eq 2 ] && grep -q "product or difference" <<<"$out"
set +e
out=$("$idrig" identify --method pole-residue --data "$dir/modes.csv" --option max_residual_poles=-1 2>&1); rc=$?
set -e
[ $rc -eq 2 ] && grep -q "max_residual_poles' must be >= 0" <<<"$out"
set +e
out=$("$idrig" identify --method pole-residue --data "$dir/modes.csv" --option weight=relative 2>&1); rc=$?
set -e
[ $rc -eq 2 ] && grep -q "inverse_magnitude" <<<"$out"
printf 'f_hz,re,im\n1,1,0\n2,0,0\n3,1,1\n4,1,2\n5,1,3\n6,2,1\n7,1,1\n' > "$dir/zero.csv"
set +e
out=$("$idrig" identify --method pole-residue --data "$dir/zero.csv" --option weight=inverse_magnitude 2>&1); rc=$?
set -e
[ $rc -eq 2 ] && grep -q "|H| is 0 at 2 Hz" <<<"$out"
echo "cli.frequency_methods: ok"
