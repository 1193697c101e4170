#!/usr/bin/env bash
# idrig identify --method step-prony / modal-polyref --json on records written by idrig itself:
#  - a unit step (idrig excite) through K(p) = 4.25/((p+1)^2 (p^2+p+4.25)) (idrig simulate):
#    the double pole at -1 and the pair -0.5 +- 2j come back, with multiplicity 2;
#  - a 3-DOF chain (2 forces, 3 displacements) under uniform random forces: the three natural
#    frequencies 2.23986, 6.27595, 9.06901 Hz come back within 0.1 %.
set -euo pipefail
idrig=$1
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT

cat > "$dir/plant.json" <<'JSON'
{"format":"idrig.model/1","kind":"tf","domain":"continuous","Ts":0,"num":[4.25],"den":[1,3,7.25,9.5,4.25],"delay_s":0}
JSON
"$idrig" excite --signal step:amp=1,at=0 --fs 200 --duration 10 --out "$dir/u.csv"
awk -F, 'NR == 1 { print $0 ",y"; next } { print $0 ",0" }' "$dir/u.csv" > "$dir/u_y.csv"
"$idrig" simulate --model "$dir/plant.json" --data "$dir/u_y.csv" --out "$dir/step.csv"
"$idrig" identify --data "$dir/step.csv" --method step-prony --json > "$dir/step.json"
grep -q '"format": "idrig.model/1"' "$dir/step.json"
grep -q '"method": "step-prony"' "$dir/step.json"
grep -q '"order_table"' "$dir/step.json"
grep -q '"lp_condition_number"' "$dir/step.json"
# Multiplicities 2 (the double pole) and 1 (the pair), order 4.
grep -q '"multiplicity": 2' "$dir/step.json"
grep -q '"multiplicity": 1' "$dir/step.json"
# Denominator (p+1)^2 (p^2+p+4.25) = p^4 + 3p^3 + 7.25p^2 + 9.5p + 4.25 (to 1e-6).
tr -d ' \n' < "$dir/step.json" | grep -o '"den":\[[^]]*\]' | tr -d '"den:[]' | awk -F, '
  { split("1 3 7.25 9.5 4.25", ref, " "); if (NF != 5) { print "den has " NF " entries"; exit 1 }
    for (i = 1; i <= 5; ++i) { d = $i - ref[i]; if (d < 0) d = -d; if (d > 1e-6 * ref[i]) { print "den[" i "] = " $i; exit 1 } }
    print "step-prony denominator ok: " $0 }'
# The JSON model simulates again.
"$idrig" simulate --model "$dir/step.json" --data "$dir/u_y.csv" --out "$dir/step_sim.csv"

cat > "$dir/chain.json" <<'JSON'
{"format":"idrig.model/1","kind":"ss","domain":"continuous","Ts":0,"delay_s":0,
 "A":[[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1],[-2000,1000,0,-1.5,0.5,0],[1000,-2000,1000,0.5,-1.5,0.5],[0,1000,-1000,0,0.5,-1]],
 "B":[[0,0],[0,0],[0,0],[1,0],[0,0],[0,1]],
 "C":[[1,0,0,0,0,0],[0,1,0,0,0,0],[0,0,1,0,0,0]],
 "D":[[0,0],[0,0],[0,0]]}
JSON
awk 'BEGIN { srand(1); print "t,u1,u2,y1,y2,y3";
             for (k = 0; k < 6000; k++) printf "%.6f,%.6f,%.6f,0,0,0\n", k * 0.02, 2 * rand() - 1, 2 * rand() - 1 }' \
  > "$dir/mimo_u.csv"
"$idrig" simulate --model "$dir/chain.json" --data "$dir/mimo_u.csv" --out "$dir/mimo.csv"
"$idrig" identify --data "$dir/mimo.csv" --method modal-polyref --option modes=3 --json > "$dir/modal.json"
grep -q '"method": "modal-polyref"' "$dir/modal.json"
grep -q '"stabilisation_diagram"' "$dir/modal.json"
grep -q '"mac"' "$dir/modal.json"
grep -q 'FIR least squares' "$dir/modal.json"
tr -d ' \n' < "$dir/modal.json" | grep -o '"natural_frequency_hz":[0-9.e+-]*' | cut -d: -f2 | awk '
  { f[NR] = $1 } END { split("2.23986 6.27595 9.06901", ref, " ");
    if (NR != 3) { print NR " modes"; exit 1 }
    for (i = 1; i <= 3; ++i) { d = (f[i] - ref[i]) / ref[i]; if (d < 0) d = -d;
      printf "mode %d: %.5f Hz (true %s, %.4f %%)\n", i, f[i], ref[i], 100 * d; if (d > 1e-3) exit 1 } }'
"$idrig" simulate --model "$dir/modal.json" --data "$dir/mimo_u.csv" --out "$dir/mimo_sim.csv"
# Bad input: a step record that never settles.
awk -F, 'NR == 1 { print "t,u,y"; next } { print $1 "," $2 "," $1 }' "$dir/u.csv" > "$dir/ramp.csv"
if "$idrig" identify --data "$dir/ramp.csv" --method step-prony 2> "$dir/err.txt"; then exit 1; fi
grep -q "never settles" "$dir/err.txt"
echo "cli.step_modal: ok"
