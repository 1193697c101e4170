#!/usr/bin/env bash
# idrig excite writes a multisine and a PRBS (header, length, period), rejects a bad SPEC and an
# over-limit amplitude with exit status 2; and idrig identify --method finite-frequency
# --frequencies … --json identifies plant (40) of [Aleksandrov] from a record made by
# idrig excite + idrig simulate.
source "$(dirname "$0")/lib/common.bash"

# --- PRBS: 5-bit maximum-length sequence, 2 periods of 31 samples at fs = 100 Hz.
"$idrig" excite --signal prbs:bits=5,amp=1 --fs 100 --duration 0.62 --out "$dir/prbs.csv" \
  || fail "excite prbs"
[ "$(head -1 "$dir/prbs.csv")" = "t,u" ] || fail "prbs header: $(head -1 "$dir/prbs.csv")"
[ "$(wc -l < "$dir/prbs.csv")" -eq 63 ] || fail "prbs: $(wc -l < "$dir/prbs.csv") lines, expected 1 + 62"
# Values ±1, period 31 samples, and one period holds 16 ones and 15 minus ones (m-sequence).
awk -F, 'NR > 1 { u[NR - 2] = $2; t[NR - 2] = $1 }
  END { for (k = 0; k < 62; ++k) { if (u[k] != 1 && u[k] != -1) exit 1;
          if (t[k] + 0 < k / 100 - 1e-12 || t[k] + 0 > k / 100 + 1e-12) exit 2 }
        for (k = 0; k < 31; ++k) { if (u[k] != u[k + 31]) exit 3; s += u[k] }
        exit (s == 1 ? 0 : 4) }' "$dir/prbs.csv" || fail "prbs values/time/period (awk status $?)"

# --- Multisine (5): ω_b = 2π·0.05 rad/s (T_b = 20 s), lines 1, 4, 16, ρ = 0.5, zero phases.
"$idrig" excite --signal "multisine:f0=0.05,lines=1;4;16,amp=0.5" --fs 100 --duration 120 \
  --out "$dir/ms.csv" || fail "excite multisine"
[ "$(head -1 "$dir/ms.csv")" = "t,u" ] || fail "multisine header"
[ "$(wc -l < "$dir/ms.csv")" -eq 12001 ] || fail "multisine: $(wc -l < "$dir/ms.csv") lines, expected 1 + 12000"
# u(t) = Σ 0.5 sin(2π·0.05·n·t) at every sample, and u(t + T_b) = u(t).
awk -F, 'NR > 1 { k = NR - 2; u[k] = $2; pi = atan2(0, -1); e = 0
    for (i = 1; i <= 3; ++i) { n = (i == 1 ? 1 : (i == 2 ? 4 : 16)); e += 0.5 * sin(2 * pi * 0.05 * n * $1) }
    d = $2 - e; if (d < 0) d = -d; if (d > m) m = d }
  END { for (k = 0; k + 2000 < 12000; ++k) { d = u[k] - u[k + 2000]; if (d < 0) d = -d; if (d > p) p = d }
        printf "multisine: max |u - Eq. (5)| = %g, max |u(t + T_b) - u(t)| = %g\n", m, p
        exit (m < 1e-12 && p < 1e-12 ? 0 : 1) }' "$dir/ms.csv" || fail "multisine values/period"

# --- Bad input: exit status 2 and a message naming the problem.
expect "unknown key 'bogus' for multisine" \
  "$idrig" excite --signal "multisine:f0=0.05,bogus=1" --fs 100 --duration 1 --out "$dir/bad.csv"
expect "unknown signal kind 'nope'" \
  "$idrig" excite --signal "nope:amp=1" --fs 100 --duration 1 --out "$dir/bad.csv"
expect "above the amplitude bound 1" \
  "$idrig" excite --signal "multisine:f0=0.05,lines=1;4;16,amp=0.5" --fs 100 --duration 20 \
  --max-abs 1 --out "$dir/bad.csv"

# --- idrig simulate: plant (40) w(s) = 25(−0.4s + 1)/((5s + 1)(s² + 6s + 25)) on the same
# multisine at fs = 1 kHz for 140 s (7 base periods).
"$idrig" excite --signal "multisine:f0=0.05,lines=1;4;16,amp=0.5" --fs 1000 --duration 140 \
  --out "$dir/ms1k.csv" || fail "excite multisine 1 kHz"
cat > "$dir/plant40.json" <<'JSON'
{"format": "idrig.model/1", "kind": "tf", "domain": "continuous", "Ts": 0.0, "delay_s": 0.0,
 "num": [-0.4, 1.0], "den": [0.2, 1.24, 5.24, 1.0]}
JSON
# simulate drives the model by the record's input columns; it needs an output column too.
awk -F, 'NR == 1 { print "t,u,y"; next } { print $1 "," $2 ",0" }' "$dir/ms1k.csv" > "$dir/input.csv"
"$idrig" simulate --model "$dir/plant40.json" --data "$dir/input.csv" --out "$dir/rec.csv" \
  || fail "simulate"

# --- idrig identify --method finite-frequency --frequencies … --json
w=$(awk 'BEGIN { printf "%.17g,%.17g,%.17g", 0.1 * atan2(0, -1), 0.4 * atan2(0, -1), 1.6 * atan2(0, -1) }')
wb=$(awk 'BEGIN { printf "%.17g", 0.1 * atan2(0, -1) }')
"$idrig" identify --data "$dir/rec.csv" --method finite-frequency --order 3 \
  --option numerator_degree=1 --option base_omega="$wb" --frequencies "$w" \
  --option skip_base_periods=2 --option filter_time=80 --json > "$dir/ff.json" \
  || fail "identify finite-frequency"
jq -e '.format == "idrig.model/1" and .identification.method == "finite-frequency"
       and .identification.status == "ok" and (.identification.details.test_frequencies | length) == 3
       and .identification.details.base_periods == 4' "$dir/ff.json" > /dev/null \
  || fail "finite-frequency JSON report: $(head -c 600 "$dir/ff.json")"
# The record is the exact ZOH response to the sampled multisine (h = 1 ms): the identified
# w is w(jω)·e^(−jωh/2)·sinc(ωh/2) at the test lines, a half-sample delay (2.5 mrad at 5 rad/s)
# that moves d_3 by ≈ 0.3 % (2.8 % at h = 10 ms); tolerance 1 %. Reference: plant (40) itself.
jq -r '.identification.details | [.d[0] / 5.24, .d[1] / 1.24, .d[2] / 0.2, .k[0] / 1.0, .k[1] / -0.4,
       .amplitudes[0], .amplitudes[1], .amplitudes[2]] | @tsv' "$dir/ff.json" |
  awk '{ printf "finite-frequency: d/d_true = %.4f %.4f %.4f, k/k_true = %.4f %.4f, rho = %.6f %.6f %.6f\n", $1, $2, $3, $4, $5, $6, $7, $8
         for (i = 1; i <= 5; ++i) { e = $i - 1; if (e < 0) e = -e; if (e > 0.01) bad = 1 }
         for (i = 6; i <= 8; ++i) { e = $i - 0.5; if (e < 0) e = -e; if (e > 1e-9) bad = 1 }
         exit bad }' || fail "finite-frequency coefficients not within 1 % of plant (40)"
"$idrig" identify --data "$dir/rec.csv" --method finite-frequency --order 3 \
  --option numerator_degree=1 --option base_omega="$wb" --frequencies "$w" \
  --option skip_base_periods=2 --option filter_time=80 > "$dir/ff.txt" || fail "identify (text)"
grep -q "finite-frequency identification" "$dir/ff.txt" || fail "text report: $(cat "$dir/ff.txt")"

# --- --frequencies: bad lists and methods that do not take it.
expect "method 'arx' does not" \
  "$idrig" identify --data "$dir/rec.csv" --method arx --order 3 --frequencies "$w"
expect "unknown method 'nope'" \
  "$idrig" identify --data "$dir/rec.csv" --method nope --frequencies "$w"
expect "got ''" \
  "$idrig" identify --data "$dir/rec.csv" --method finite-frequency --order 3 \
  --option base_omega="$wb" --frequencies ""
expect "got 'abc'" \
  "$idrig" identify --data "$dir/rec.csv" --method finite-frequency --order 3 \
  --option base_omega="$wb" --frequencies "0.3,abc"
expect "not an integer multiple of the base frequency" \
  "$idrig" identify --data "$dir/rec.csv" --method finite-frequency --order 3 \
  --option numerator_degree=1 --option base_omega="$wb" --frequencies "0.3141592653589793,1.3,5.0265482457436690"
expect "given twice" \
  "$idrig" identify --data "$dir/rec.csv" --method finite-frequency --order 3 \
  --option base_omega="$wb" --option "frequencies=[1]" --frequencies "$w"
[ $status -eq 0 ] && echo "cli.excite_finite_frequency: ok"
exit $status
