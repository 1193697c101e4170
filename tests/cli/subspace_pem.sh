#!/usr/bin/env bash
# idrig identify without --method on idrig's own example record (third-order plant) chooses an
# order-3 model and prints the candidate table; n4sid identifies a 2x2 MIMO record with a fit
# per output; oe reports standard errors; bad MIMO input is refused with exit status 2.
source "$(dirname "$0")/lib/common.bash"
"$idrig" example --out "$dir/ex.csv" --model-out "$dir/plant.json" 2>/dev/null
out=$("$idrig" identify --data "$dir/ex.csv") || fail "identify (default method) failed"
grep -q "Method and order chosen on held-out data" <<<"$out" || fail "no candidate table: $out"
grep -Eq "^chosen: [a-z0-9-]+ order 3 " <<<"$out" || fail "default did not choose order 3: $(grep '^chosen' <<<"$out")"
json=$("$idrig" identify --data "$dir/ex.csv" --json) || fail "identify --json failed"
grep -q '"chosen_method"' <<<"$json" || fail "no chosen_method in the JSON report"

# oe: standard errors in the text and in the JSON.
out=$("$idrig" identify --data "$dir/ex.csv" --method oe --order 3) || fail "oe failed"
grep -q "F(q) = 1 - 2.4" <<<"$out" || fail "oe: no F(q) with standard errors: $out"
grep -q "(±" <<<"$out" || fail "oe: no standard errors in the text"
json=$("$idrig" identify --data "$dir/ex.csv" --method oe --order 3 --json)
grep -q '"std"' <<<"$json" || fail "oe: no std in JSON"

# A 2x2 MIMO record: the plant on u1, twice the plant on u2 = u1 delayed by 700 samples
# (cyclically), y1 = G u1 + 0.5 G u2, y2 = G u2 (noise-free, order 6 in total).
awk -F, 'NR == 1 { next } { t[NR-2] = $1; u[NR-2] = $2; n = NR-1 }
  END { print "t,u,y"; for (k = 0; k < n; k++) printf "%s,%s,0\n", t[k], u[(k + 700) % n] }' "$dir/ex.csv" > "$dir/u2.csv"
"$idrig" simulate --model "$dir/plant.json" --data "$dir/ex.csv" --out "$dir/y1.csv"
"$idrig" simulate --model "$dir/plant.json" --data "$dir/u2.csv" --out "$dir/y2.csv"
paste -d, "$dir/y1.csv" "$dir/y2.csv" | awk -F, 'NR == 1 { print "t,u1,u2,y1,y2"; next }
  { printf "%s,%s,%s,%.17g,%.17g\n", $1, $2, $5, $3 + 0.5 * $6, $6 }' > "$dir/mimo.csv"
out=$("$idrig" identify --data "$dir/mimo.csv" --method n4sid --order 6) || fail "n4sid MIMO failed"
grep -Eq "fit .*y1 (99\.9[0-9]*|100) %, y2 (99\.9[0-9]*|100) %" <<<"$out" || fail "n4sid MIMO fit per output: $(grep fit <<<"$out")"
out=$("$idrig" identify --data "$dir/mimo.csv" --method oe --order 3) || fail "oe MIMO failed"
grep -q "one MISO model per output" <<<"$out" || fail "oe MIMO: not per output"
grep -Eq "y1 (99\.9[0-9]*|100) %, y2 (99\.9[0-9]*|100) %" <<<"$out" || fail "oe MIMO fit per output: $(tail -1 <<<"$out")"

# Bad input: too few samples for the block rows; columns that do not split into inputs and
# outputs; two identical inputs; a constant input.
head -101 "$dir/mimo.csv" > "$dir/short.csv"
expect "too few samples for the block rows" "$idrig" identify --data "$dir/short.csv" --method n4sid --option block_rows=20
awk -F, '{ print $1 "," $2 "," $3 }' "$dir/mimo.csv" | sed '1s/.*/t,u1,u2/' > "$dir/noout.csv"
expect "no output column" "$idrig" identify --data "$dir/noout.csv" --method n4sid
awk -F, 'NR == 1 { print; next } { print $1 "," $2 "," $2 "," $4 "," $5 }' "$dir/mimo.csv" > "$dir/twins.csv"
expect "linearly dependent" "$idrig" identify --data "$dir/twins.csv" --method n4sid
expect "linearly dependent" "$idrig" identify --data "$dir/twins.csv" --method oe --order 2
awk -F, 'NR == 1 { print; next } { print $1 "," $2 ",0.5," $4 "," $5 }' "$dir/mimo.csv" > "$dir/const.csv"
expect "input 2 is constant" "$idrig" identify --data "$dir/const.csv" --method n4sid
expect "unknown option 'blocks'" "$idrig" identify --data "$dir/mimo.csv" --method n4sid --option blocks=3
expect "weighting 'pca'" "$idrig" identify --data "$dir/mimo.csv" --method n4sid --option weighting=pca
# A rig run about an operating point: the example record with its command 0.7 higher and its
# reading 5 higher. auto fits about the means (a "mean" candidate wins), the model carries its
# operating point, and `idrig simulate` reproduces the offset record with it (fit > 90 %; the
# noise of the example record leaves 93 %, as the plain fit of the plain record).
awk -F, 'NR == 1 { print; next } { printf "%s,%.17g,%.17g\n", $1, $2 + 0.7, $3 + 5 }' "$dir/ex.csv" > "$dir/op.csv"
out=$("$idrig" identify --data "$dir/op.csv") || fail "identify on an offset record failed"
grep -Eq "^chosen: [a-z0-9= -]+ mean order 3 " <<<"$out" || fail "offset record: no 'mean' order-3 choice: $(grep '^chosen' <<<"$out")"
"$idrig" identify --data "$dir/op.csv" --method oe --order 3 --offsets mean --json > "$dir/op.json" || fail "oe --offsets mean failed"
grep -q '"operating_point"' "$dir/op.json" || fail "no operating_point in the model"
"$idrig" simulate --model "$dir/op.json" --data "$dir/op.csv" --out "$dir/op-sim.csv" || fail "simulate about the operating point failed"
fit=$(paste -d, "$dir/op.csv" "$dir/op-sim.csv" | awk -F, 'NR > 1 { y[NR] = $3; s[NR] = $6; m += $3; n++ }
  END { m /= n; for (k in y) { e += (y[k] - s[k])^2; d += (y[k] - m)^2 } printf "%.1f", 100 * (1 - sqrt(e / d)) }')
awk -v f="$fit" 'BEGIN { exit !(f > 90) }' || fail "simulate about the operating point: fit $fit %"
expect "--offsets: median not in" "$idrig" identify --data "$dir/op.csv" --offsets median
"$idrig" identify --data "$dir/op.csv" --method oe --order 3 --offsets initial --json | grep -q '"source": "initial rest"' \
  || fail "--offsets initial: no initial-rest operating point"
expect "is for the method auto" "$idrig" identify --data "$dir/op.csv" --method oe --offsets auto
printf '{"format":"idrig.model/1","kind":"tf","num":[1],"den":[1,1],"operating_point":{"u":[1,2],"y":[0]}}' > "$dir/op-bad.json"
expect "\"operating_point\" has 2 input and 1 output values" "$idrig" simulate --model "$dir/op-bad.json" --data "$dir/op.csv"

# A rig's own column names: the same record as stamp,mode,force,position (an extra column left
# out) gives the same model as t,u,y; gap diagnose reads such records too; a missing column and
# a lone --u are named.
awk -F, 'NR == 1 { print "stamp,mode,force,position"; next } { print $1 ",3," $2 "," $3 }' "$dir/op.csv" > "$dir/rig.csv"
a=$("$idrig" identify --data "$dir/op.csv" --method oe --order 3 --offsets mean | tail -1)
b=$("$idrig" identify --data "$dir/rig.csv" --u force --y position --time stamp --method oe --order 3 --offsets mean | tail -1)
[ -n "$a" ] && [ "$a" = "$b" ] || fail "named columns: '$b' against '$a'"
head -601 "$dir/rig.csv" > "$dir/rig-est.csv"; { head -1 "$dir/rig.csv"; tail -n +602 "$dir/rig.csv"; } > "$dir/rig-val.csv"
"$idrig" identify --data "$dir/rig-est.csv" --u force --y position --time stamp --method oe --order 3 --json > "$dir/rig-sim.json"
"$idrig" gap diagnose --sim "$dir/rig-sim.json" --data "$dir/rig-est.csv" --validate "$dir/rig-val.csv" \
  --u force --y position --time stamp --json > "$dir/rig-gap.json" || fail "gap diagnose on named columns failed"
grep -q '"verdict"' "$dir/rig-gap.json" || fail "gap diagnose on named columns: no verdict"
expect "no column 'pos' (output) in the header; its columns: stamp, mode, force, position" \
  "$idrig" identify --data "$dir/rig.csv" --u force --y pos --time stamp
expect "need both --u and --y" "$idrig" identify --data "$dir/rig.csv" --u force
expect "column 'stamp' is not t, u… or y…" "$idrig" identify --data "$dir/rig.csv"
expect "need both --u and --y" "$idrig" gap diagnose --sim "$dir/rig-sim.json" --data "$dir/rig-est.csv" --y position

[ $status -eq 0 ] && echo "cli.subspace_pem: ok"
exit $status
