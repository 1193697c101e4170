#!/usr/bin/env bash
# Each bad input gives exit code 2 and a message naming the problem.
source "$(dirname "$0")/lib/common.bash"
printf 't,u,y\n0,1,0\n0.1,nan,0\n0.2,1,0\n' > "$dir/nan.csv"
printf 't,u,y\n0,1,0\n0.1,1,0\n0.1,1,0\n' > "$dir/time.csv"
printf 't,x,y\n0,1,0\n0.1,1,0\n' > "$dir/cols.csv"
printf 't,u,y\n0,1,0\n0.1,1,0\n0.2,2' > "$dir/trunc.csv"
: > "$dir/empty.csv"
"$idrig" example --out "$dir/short.csv" --samples 30 --noise 0
awk -F, 'NR == 1 { print; next } { print $1 ",1," $3 }' "$dir/short.csv" > "$dir/const.csv"
expect "NaN in input column 'u' at sample 1" "$idrig" identify --data "$dir/nan.csv"
expect "not increasing at sample 2" "$idrig" identify --data "$dir/time.csv"
expect "column 'x'" "$idrig" identify --data "$dir/cols.csv"
expect "line 4 has 2 fields" "$idrig" identify --data "$dir/trunc.csv"
expect "empty file" "$idrig" identify --data "$dir/empty.csv"
expect "cannot open" "$idrig" identify --data "$dir/none.csv"
expect "persistently exciting" "$idrig" identify --data "$dir/const.csv" --order 2
expect "equations" "$idrig" identify --data "$dir/short.csv" --order 15
expect "unknown method 'nope'" "$idrig" identify --data "$dir/short.csv" --method nope
expect "unknown option 'ordr'" "$idrig" identify --data "$dir/short.csv" --option ordr=3
expect "option 'min_fit_percent' must be a number" "$idrig" identify --data "$dir/short.csv" --order 2 --option min_fit_percent=high
"$idrig" example --out "$dir/prbs.csv" --samples 600 --noise 0
expect "not a multisine test signal (5)" "$idrig" identify --data "$dir/prbs.csv" --method finite-frequency --order 2
printf 'f_hz,re,im,sigma\n1,1,0,0.1\n2,0.5,0,0\n' > "$dir/sigma.csv"
expect "field 4 (sigma) must be > 0" "$idrig" identify --data "$dir/sigma.csv" --method levy-sk --order 1
echo '{"format":"idrig.model/1","kind":"tf"' > "$dir/bad.json"
expect "not valid JSON" "$idrig" simulate --model "$dir/bad.json" --data "$dir/short.csv"
exit $status
