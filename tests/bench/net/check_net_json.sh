#!/usr/bin/env bash
# Runs a 5 s microdex-bench net and checks that its JSON has every field with a number.
set -euo pipefail
bench="$1"
json="$2"
rm -f "$json"
"$bench" net --json "$json" --duration 5 --domain 91
for key in stations period_p99_ms period_p999_ms period_max_ms overruns latency_p50_us \
           latency_p99_us input_lost instructor_cpu; do
  grep -Eq "\"$key\": -?[0-9]+(\.[0-9]+)?,?$" "$json" || { echo "missing or not a number: $key"; cat "$json"; exit 1; }
done
grep -q '"stations": 4,' "$json" || { echo "expected 4 stations"; exit 1; }
echo "net bench JSON: ok"
