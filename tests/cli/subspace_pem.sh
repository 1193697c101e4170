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
[ $status -eq 0 ] && echo "cli.subspace_pem: ok"
exit $status
