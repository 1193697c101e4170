#!/usr/bin/env bash
# idrig gap diagnose / bench through the real binary: a generated case with a withheld effect
# (written by `gap bench --dump`), the JSON interface scripts depend on, and bad input.
source "$(dirname "$0")/lib/common.bash"

# Cases cycle through the vocabulary: case 1 is parameter_mismatch, case 2 time_delay.
"$idrig" gap bench --cases 3 --seed 5 --samples 2000 --dump "$dir" --json > "$dir/bench.json" 2>/dev/null \
  || fail "gap bench exited with $?"
grep -q '"top1_accuracy"' "$dir/bench.json" || fail "bench JSON lacks top1_accuracy"
grep -q '"effect": "time_delay"' "$dir/case2-truth.json" || fail "case 2 is not a time_delay case"

out=$("$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/case2-est.csv" \
      --validate "$dir/case2-val.csv" --json) || fail "gap diagnose exited with $?"
for key in '"verdict"' '"confidence"' '"nrmse_before"' '"nrmse_after"' '"params"' '"ranking"' \
           '"where"' '"score"' '"tau_s"'; do
  grep -q -- "$key" <<<"$out" || fail "diagnose JSON lacks $key"
done
verdict=$(grep -m1 '"effect":' <<<"$out" | sed 's/.*"effect": "\([a-z_]*\)".*/\1/')
[ "$verdict" = "time_delay" ] || fail "verdict '$verdict', expected time_delay"
echo "ok: time_delay case diagnosed as $verdict"

# The stored report renders again as text, with SVG plots.
"$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/case2-est.csv" \
  --validate "$dir/case2-val.csv" --json --plots "$dir/plots" > "$dir/report.json" 2>/dev/null \
  || fail "gap diagnose --plots exited with $?"
rendered=$("$idrig" gap report "$dir/report.json" --plots "$dir/plots2") || fail "gap report exited with $?"
grep -q "^verdict: time_delay" <<<"$rendered" || fail "report text: $rendered"
for plot in gap_frequency gap_amplitude gap_state gap_time gap_ranking; do
  for d in plots plots2; do
    grep -q "^<svg" "$dir/$d/$plot.svg" 2>/dev/null || fail "$d/$plot.svg missing or not SVG"
    grep -q "</svg>" "$dir/$d/$plot.svg" 2>/dev/null || fail "$d/$plot.svg truncated"
  done
done
cmp -s "$dir/plots/gap_ranking.svg" "$dir/plots2/gap_ranking.svg" || fail "plots differ between diagnose and report"
echo "ok: report and plots"

# One record only: split in time, said in the notes; text output names the verdict.
text=$("$idrig" gap diagnose --sim "$dir/case1-sim.json" --data "$dir/case1-est.csv") \
  || fail "gap diagnose (one record) exited with $?"
grep -q "first half" <<<"$text" || fail "no note about the split: $text"
grep -q "^verdict:" <<<"$text" || fail "no verdict line: $text"
echo "ok: one record split"

awk -F, 'NR == 1 { print; next } NR == 40 { print $1 "," $2 ",nan"; next } { print }' \
  "$dir/case2-est.csv" > "$dir/nan.csv"
awk -F, 'NR == 1 { print; next } { print $1 ",0.5," $3 }' "$dir/case2-est.csv" > "$dir/const.csv"
head -40 "$dir/case2-est.csv" > "$dir/short.csv"
echo '{"format":"idrig.model/1","kind":"tf","domain":"discrete","Ts":0.5,"num":[0.5],"den":[1,-0.5]}' \
  > "$dir/discrete.json"
expect "NaN" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/nan.csv"
expect "the input is constant" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/const.csv" --validate "$dir/case2-val.csv"
expect "too short to split" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/short.csv"
expect "sample time" "$idrig" gap diagnose --sim "$dir/discrete.json" --data "$dir/case2-est.csv"
expect "cannot open" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/missing.csv"
expect "not a gap report" "$idrig" gap report "$dir/case2-sim.json"
echo '{"format":' > "$dir/broken.json"
expect "not valid JSON" "$idrig" gap report "$dir/broken.json"
exit $status
