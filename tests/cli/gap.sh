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

# A parameter mismatch is listed under verdict.effects too (its parameters are the refitted
# plant, verdict.plant): scripts that read `effects` see what `effect` says.
out=$("$idrig" gap diagnose --sim "$dir/case1-sim.json" --data "$dir/case1-est.csv" \
      --validate "$dir/case1-val.csv" --json) || fail "gap diagnose (case 1) exited with $?"
jq -e '.verdict.effect == "parameter_mismatch" and (.verdict.effects | length) == 1
       and .verdict.effects[0].effect == "parameter_mismatch" and (.verdict.plant.num | length) > 0' \
  <<<"$out" > /dev/null || fail "parameter mismatch not listed in verdict.effects: $(jq -c '.verdict | {effect, effects}' <<<"$out")"
echo "ok: parameter_mismatch in verdict.effects"

# A sensor glitch (one reading 50 output ranges off) is bridged and reported, not diagnosed; a
# record with a stretch cut out is refused at the jump.
awk -F, 'NR == 1 { print; next } NR == 901 { print $1 "," $2 "," ($3 + 50); next } { print }' \
  "$dir/case2-est.csv" > "$dir/glitch.csv"
out=$("$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/glitch.csv" \
      --validate "$dir/case2-val.csv" --json) || fail "gap diagnose (glitch) exited with $?"
jq -e '.verdict.effect == "time_delay" and (.glitches | length) == 1 and .glitches[0].sample == 899
       and .glitches[0].records == "estimation"' <<<"$out" > /dev/null \
  || fail "glitch not bridged and reported: $(jq -c '[.verdict.effect, .glitches]' <<<"$out")"
out=$("$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/glitch.csv" \
      --validate "$dir/case2-val.csv" --glitches keep --json) || fail "gap diagnose --glitches keep exited with $?"
jq -e '(.glitches | length) == 0' <<<"$out" > /dev/null || fail "--glitches keep still bridged: $(jq -c .glitches <<<"$out")"
expect "glitches" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/glitch.csv" --glitches drop
"$idrig" gap bench --cases 1 --seed 4 --samples 600 --add-glitches 2 --glitches keep --json > "$dir/gl.json" 2>/dev/null \
  || fail "gap bench --add-glitches exited with $?"
jq -e '.add_glitches == 2 and .glitches == "keep"' "$dir/gl.json" > /dev/null || fail "bench JSON lacks add_glitches/glitches"

# A sensor that drifts (a ramp of 15 noise sigmas, up over the estimation record, down over the
# validation one): a nuisance parameter reported per estimation record, not an effect.
sigma=$(jq .noise_sigma "$dir/case2-truth.json")
for part in est val; do
  awk -F, -v sg="$sigma" -v sign="$([ $part = est ] && echo 1 || echo -1)" \
    'NR == 1 { print; next } { printf "%s,%s,%.10g\n", $1, $2, $3 + sign * 15 * sg * (NR - 2) / 1999 }' \
    "$dir/case2-$part.csv" > "$dir/drift-$part.csv"
done
out=$("$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/drift-est.csv" --validate "$dir/drift-val.csv" \
      --json) || fail "gap diagnose on a drifting record exited with $?"
jq -e --argjson s "$sigma" '.verdict.effect == "time_delay" and (.verdict.nuisance.output_drift | length) == 1
       and (.verdict.nuisance.output_drift[0] - 15 * $s / 19.99 | fabs) < 3 * $s / 19.99' <<<"$out" > /dev/null \
  || fail "drift not taken as a nuisance: $(jq -c '[.verdict.effect, .verdict.nuisance]' <<<"$out")"
out=$("$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/drift-est.csv" --validate "$dir/drift-val.csv" \
      --drift none --json) || fail "gap diagnose --drift none exited with $?"
jq -e '.verdict.nuisance | has("output_drift") | not' <<<"$out" > /dev/null || fail "--drift none still fitted a drift"
expect "drift" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/drift-est.csv" --drift maybe
echo "ok: a sensor drift is a nuisance parameter (--drift fit|none)"

# A sensor re-zeroed part way through the estimation record (8 noise sigmas): the step is found
# and reported (a sensor level of its own from there on); --sensor-steps ignore fits as measured.
sigma0=$(jq .noise_sigma "$dir/case0-truth.json")
awk -F, -v sg="$sigma0" 'NR == 1 { print; next } { printf "%s,%s,%.10g\n", $1, $2, $3 + (NR - 2 >= 1200 ? 8 * sg : 0) }' \
  "$dir/case0-est.csv" > "$dir/step-est.csv"
out=$("$idrig" gap diagnose --sim "$dir/case0-sim.json" --data "$dir/step-est.csv" --validate "$dir/case0-val.csv" \
      --json) || fail "gap diagnose on a stepping sensor exited with $?"
jq -e '(.sensor_steps | length) == 1 and .sensor_steps[0].records == "estimation" and .sensor_steps[0].sample == 1200' \
  <<<"$out" > /dev/null || fail "sensor step not found: $(jq -c '[.verdict.effect, .sensor_steps]' <<<"$out")"
out=$("$idrig" gap diagnose --sim "$dir/case0-sim.json" --data "$dir/step-est.csv" --validate "$dir/case0-val.csv" \
      --sensor-steps ignore --json) || fail "gap diagnose --sensor-steps ignore exited with $?"
jq -e '(.sensor_steps | length) == 0' <<<"$out" > /dev/null || fail "--sensor-steps ignore still marked a step"
expect "sensor-steps" "$idrig" gap diagnose --sim "$dir/case0-sim.json" --data "$dir/step-est.csv" --sensor-steps cut
echo "ok: a sensor step gets a level of its own (--sensor-steps find|ignore)"
awk 'NR <= 500 || NR > 700' "$dir/case2-est.csv" > "$dir/spliced.csv"
expect "not uniform at sample 499: t jumps" "$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/spliced.csv"
echo "ok: a glitch bridged, a splice refused"

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
# --- issue 13: bench with operating points and pairs; noise floor, lattice and detection lines.
"$idrig" gap bench --cases 2 --seed 3 --samples 1000 --offsets --combos 0.5 --dump "$dir/pairs" --json \
  > "$dir/pairs.json" 2>/dev/null || fail "gap bench --offsets --combos exited with $?"
for key in '"combo_both_named"' '"combo_top1_either"' '"combo_cases": 1' '"offsets": true' '"single_cases": 1'; do
  grep -q -- "$key" "$dir/pairs.json" || fail "bench JSON lacks $key"
done
jq -e '(.effects | length) == 2 and .input_offset != 0 and .output_offset != 0' "$dir/pairs/case1-truth.json" \
  > /dev/null || fail "case 1 is not a pair with offsets"
expect "must be in [0, 1]" "$idrig" gap bench --cases 1 --combos 1.5
# --pairs any: the 54 pairs in turn (case 0: time_delay with actuator_lag); an unknown set is refused.
"$idrig" gap bench --cases 1 --seed 3 --samples 600 --combos 1 --pairs any --dump "$dir/anypairs" --json \
  > "$dir/anypairs.json" 2>/dev/null || fail "gap bench --pairs any exited with $?"
jq -e '.pairs == "any" and .combo_cases == 1' "$dir/anypairs.json" > /dev/null || fail "bench JSON lacks pairs"
jq -e '[.effects[].effect] == ["time_delay", "actuator_lag"]' "$dir/anypairs/case0-truth.json" > /dev/null \
  || fail "--pairs any case 0 is not time_delay with actuator_lag"
expect "not in {rig,any}" "$idrig" gap bench --cases 1 --pairs some
echo "ok: bench with offsets and pairs"

# The bench's other excitations, integrating plants and sample time (the blind set has its own).
"$idrig" gap bench --cases 2 --seed 4 --samples 600 --ts 0.02 --excitation steps --integrating --dump "$dir/integ" \
  --json > "$dir/integ.json" 2>/dev/null || fail "gap bench --excitation steps --integrating exited with $?"
jq -e '.integrating == true and .sample_time == 0.02 and .excitation == "steps"' "$dir/integ.json" > /dev/null \
  || fail "bench JSON does not echo its settings"
jq -e '.excitation == "steps" and .real.den[-1] == 0' "$dir/integ/case1-truth.json" > /dev/null \
  || fail "case 1 is not an integrating plant under steps"
expect "noise" "$idrig" gap bench --cases 1 --excitation sweep
# The periodic multisine; one case, `none`: no single effect named right, so no median shrink.
"$idrig" gap bench --cases 1 --seed 4 --samples 600 --excitation multisine --dump "$dir/ms" --json \
  > "$dir/ms.json" 2>/dev/null || fail "gap bench --excitation multisine exited with $?"
jq -e '.excitation == "multisine" and .median_shrink_correct == null' "$dir/ms.json" > /dev/null \
  || fail "bench JSON: multisine not echoed, or a median shrink over no case"
jq -e '.excitation == "multisine"' "$dir/ms/case0-truth.json" > /dev/null || fail "case 0 is not under the multisine"
# Lightly damped plants and coloured noise; bad ranges are named.
"$idrig" gap bench --cases 1 --seed 4 --samples 600 --damping 0.02,0.1 --noise-pole 0.5 --json > "$dir/ld.json" 2>/dev/null \
  || fail "gap bench --damping --noise-pole exited with $?"
jq -e '.damping == [0.02, 0.1] and .noise_pole == 0.5' "$dir/ld.json" > /dev/null || fail "bench JSON lacks damping/noise_pole"
expect "LO <= HI" "$idrig" gap bench --cases 1 --damping 0.5,0.1
expect "noise-pole" "$idrig" gap bench --cases 1 --noise-pole 1.5
# Process noise (a load disturbance the plant colours): echoed, and a share of 1 or more named.
"$idrig" gap bench --cases 1 --seed 4 --samples 600 --process-noise 0.5 --json > "$dir/pn.json" 2>/dev/null \
  || fail "gap bench --process-noise exited with $?"
jq -e '.process_noise == 0.5' "$dir/pn.json" > /dev/null || fail "bench JSON lacks process_noise"
expect "process-noise" "$idrig" gap bench --cases 1 --process-noise 1
# Plant families; a wrong name, and a family beside --integrating, are named.
"$idrig" gap bench --cases 1 --seed 4 --samples 600 --plants two-mass --dump "$dir/tm" --json > "$dir/tm.json" 2>/dev/null \
  || fail "gap bench --plants two-mass exited with $?"
jq -e '.plants == "two-mass"' "$dir/tm.json" > /dev/null || fail "bench JSON lacks plants"
jq -e '(.real.den | length) == 5' "$dir/tm/case0-truth.json" > /dev/null || fail "case 0 is not a fourth-order plant"
expect "plants" "$idrig" gap bench --cases 1 --plants three-mass
expect "give one" "$idrig" gap bench --cases 1 --plants zeros --integrating
echo "ok: bench excitations, integrating plants, sample time"

# --only: the cases that withhold the listed effects, each the case at its index in the full
# sequence (none is index 0, 13, 26, …).
"$idrig" gap bench --cases 2 --seed 4 --samples 600 --only none --json > "$dir/only.json" 2> "$dir/only.err" \
  || fail "gap bench --only none exited with $?"
jq -e '.only == ["none"] and .single_cases == 2' "$dir/only.json" > /dev/null || fail "bench JSON: --only not echoed"
grep -q "case 13: truth none" "$dir/only.err" || fail "--only none did not keep case 13: $(cat "$dir/only.err")"
expect "unknown effect 'stiction'" "$idrig" gap bench --cases 1 --only none,stiction
echo "ok: bench --only"

# An odd multisine (lines 1, 3, …, 15 of fs/256), 8 periods, through 5/(s+5) and a sensor with a
# y² term: the even detection lines carry the distortion, the odd ones only noise.
awk 'BEGIN { srand(1); ts = 0.01; n = 256; a = exp(-5 * ts); pi = atan2(0, -1)
  for (l = 1; l <= 15; l += 2) ph[l] = 2 * pi * rand()
  print "t,u,y"; yl = 0; up = 0
  for (k = 0; k < 8 * n; k++) {
    u = 0; for (l = 1; l <= 15; l += 2) u += 0.35 * sin(2 * pi * l * k / n + ph[l])
    yl = a * yl + (1 - a) * up; up = u
    e = 0.002 * sqrt(-2 * log(1 - rand())) * cos(2 * pi * rand())
    printf "%.6f,%.10g,%.10g\n", k * ts, u, yl + 0.4 * yl * yl + e } }' > "$dir/odd.csv"
echo '{"format":"idrig.model/1","kind":"tf","domain":"continuous","num":[5],"den":[1,5]}' > "$dir/first.json"
"$idrig" gap diagnose --sim "$dir/first.json" --data "$dir/odd.csv" --json --plots "$dir/odd-plots" \
  > "$dir/odd.json" 2>/dev/null || fail "gap diagnose (odd multisine) exited with $?"
# G0's gap is the y² term, on the even lines only: no linear function of the input, whose lines are
# odd, explains it, so verdict.g0_gap is does_not_follow_input.
jq -e '.where.detection_lines as $d | .where.noise_floor as $f | .verdict as $v
  | $d.available and $d.period_samples == 256 and $d.even_distortion and ($d.odd_distortion | not)
  and $f.method == "periods" and ($f.sigma / 0.002 - 1 | fabs) < 0.15
  and (($v.remaining_gap_to_noise - ($v.nrmse_after - $v.noise_nrmse)) | fabs) < 1e-12
  and ($v.below_noise_floor or $v.shrink <= 1)
  and $v.g0_gap == "does_not_follow_input"' "$dir/odd.json" > /dev/null \
  || fail "detection lines / noise floor on the odd multisine: $(jq -c '.where.detection_lines | del(.lines)' "$dir/odd.json")"
echo "ok: detection lines and the noise floor from periods"

# A lattice: case 2's output read by a coarse ADC with an offset (step 4 % of the range); the
# same record with its continuous output has no lattice.
awk -F, 'NR == 1 { print; next } { y[NR] = $3; t[NR] = $1; u[NR] = $2; if (NR == 2 || $3 < lo) lo = $3; if (NR == 2 || $3 > hi) hi = $3 }
  END { q = 0.04 * (hi - lo); for (i = 2; i <= NR; i++) printf "%s,%s,%.10g\n", t[i], u[i], 0.37 * q + q * int((y[i] - 0.37 * q) / q + 1000.5) - 1000 * q }' \
  "$dir/case2-est.csv" > "$dir/adc.csv"
"$idrig" gap diagnose --sim "$dir/case2-sim.json" --data "$dir/adc.csv" --json > "$dir/adc.json" 2>/dev/null \
  || fail "gap diagnose (ADC) exited with $?"
jq -e '.where.lattice.lattice and .where.lattice.detected
  and ([.verdict.effect] + [.verdict.effects[]?.effect] | index("output_quantization") != null)' \
  "$dir/adc.json" > /dev/null || fail "lattice not named on the ADC record: $(jq -c '.where.lattice, .verdict.effect' "$dir/adc.json")"
echo "ok: lattice"

# A real record (DaISy exchanger, steam flow -> outlet temperature; skipped without ../shared):
# with the sim model `identify` gives on its first half, the verdict's actuator offset comes out
# at -0.06 ± 99 on an input that spans 0.6 — not an operating point, and the notes say so.
exchanger="$(dirname "$0")/../../../shared/data/daisy/exchanger.dat"
if [ -f "$exchanger" ]; then
  awk -v est="$dir/ex-est.csv" -v val="$dir/ex-val.csv" 'BEGIN { n = 0 } NF > 0 { u[n] = $2; y[n] = $3; n++ }
    END { h = int(n / 2); print "t,u,y" > est; print "t,u,y" > val
          for (i = 0; i < n; i++) printf "%d,%s,%s\n", (i < h ? i : i - h), u[i], y[i] > (i < h ? est : val) }' "$exchanger"
  "$idrig" identify --data "$dir/ex-est.csv" --json > "$dir/ex-sim.json" 2>/dev/null || fail "identify (exchanger) exited with $?"
  "$idrig" gap diagnose --sim "$dir/ex-sim.json" --data "$dir/ex-est.csv" --validate "$dir/ex-val.csv" --json \
    > "$dir/ex.json" 2>/dev/null || fail "gap diagnose (exchanger) exited with $?"
  jq -e '.verdict.nuisance.input_offset_std > 0.6
    and ([.notes[] | select(startswith("the actuator offset is not determined by these records"))] | length == 1)' \
    "$dir/ex.json" > /dev/null \
    || fail "exchanger: an undetermined actuator offset not said so: $(jq -c '.verdict.nuisance' "$dir/ex.json")"
  echo "ok: an actuator offset the records do not determine is named (exchanger)"
else
  echo "skip: ../shared/data/daisy/exchanger.dat not found"
fi
exit $status
