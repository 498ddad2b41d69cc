#!/usr/bin/env bash
# Runs a 4 s microdex-bench record and checks its JSON: every field a number, 8 stations, and
# nothing lost on the reliable paths (DeviceInput steps, the recorder's queue).
set -euo pipefail
bench="$1"
json="$2"
rm -f "$json"
"$bench" record --json "$json" --seconds 4 --domain 133
for key in stations seconds samples lost input_lost sequence_gaps recorder_dropped mb_per_min \
           recorder_cpu instructor_cpu writer_capacity_msgs_per_s; do
  grep -Eq "\"$key\": -?[0-9]+(\.[0-9]+)?,?$" "$json" || { echo "missing or not a number: $key"; cat "$json"; exit 1; }
done
grep -q '"stations": 8,' "$json" || { echo "expected 8 stations"; exit 1; }
grep -q '"input_lost": 0,' "$json" || { echo "DeviceInput samples missing"; cat "$json"; exit 1; }
grep -q '"recorder_dropped": 0,' "$json" || { echo "the recorder dropped samples"; cat "$json"; exit 1; }
echo "record bench JSON: ok"
