#!/usr/bin/env bash
# Runs a 4 s microdex-bench record and checks its JSON: every field a number, 8 stations, and
# nothing lost on any recorded topic (DeviceInput steps; the sequence numbers of every station's
# writer of StationInfo, DeviceInput, ToolState, NeedleState, Telemetry, TaskEvent, Score and
# CueOverlay: gaps and samples before the first; the recorder's queue).
set -euo pipefail
bench="$1"
json="$2"
rm -f "$json"
"$bench" record --json "$json" --seconds 4 --domain 133
for key in stations seconds samples lost input_lost sequence_gaps recorder_dropped mb_per_min \
           recorder_cpu instructor_cpu writer_capacity_msgs_per_s missing_before_first; do
  grep -Eq "\"$key\": -?[0-9]+(\.[0-9]+)?,?$" "$json" || { echo "missing or not a number: $key"; cat "$json"; exit 1; }
done
grep -q '"stations": 8,' "$json" || { echo "expected 8 stations"; exit 1; }
grep -q '"input_lost": 0,' "$json" || { echo "DeviceInput samples missing"; cat "$json"; exit 1; }
grep -q '"recorder_dropped": 0,' "$json" || { echo "the recorder dropped samples"; cat "$json"; exit 1; }
for topic in station_info device_input tool_state needle_state telemetry task_event score cue_overlay; do
  grep -Eq "\"lost_by_topic\": \{.*\"microdex/$topic\": 0[,}]" "$json" ||
    { echo "microdex/$topic: samples missing (or the topic not recorded)"; cat "$json"; exit 1; }
done
grep -q '"lost": 0,' "$json" || { echo "samples missing"; cat "$json"; exit 1; }
echo "record bench JSON: ok"
