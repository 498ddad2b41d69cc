#!/usr/bin/env bash
# Runs a quick microdex-bench fem (levels up to 5) and prints its tables with tools/fem-tables:
# every part is there, the accuracy table has the G1 and G2 rows of each level, the moving
# table a row per moving run of the JSON, and a file that is not the bench's JSON is refused
# with its name.
set -euo pipefail
bench="$1"
json="$2"
root="$(cd "$(dirname "$0")/../../.." && pwd)"
rm -f "$json"
"$bench" fem --quick --json "$json" > "$json.log" 2>&1 || { cat "$json.log"; exit 1; }
out="$("$root/tools/fem-tables" "$json")"
for part in goals accuracy fair off_grid tilted continuity moving; do
  grep -q "^### $part$" <<< "$out" || { echo "fem-tables: no part '$part'"; exit 1; }
done
accuracy="$("$root/tools/fem-tables" "$json" --only accuracy | grep -cE '^\| G[12] \| [0-9]+ \|')"
[ "$accuracy" -ge 4 ] || { echo "fem-tables: $accuracy accuracy rows (expected G1 and G2 at 2 levels or more)"; exit 1; }
rows="$("$root/tools/fem-tables" "$json" --only moving | grep -cE '^\| [0-9]+ \|')"
runs="$(grep -o '"attached_mesh"' "$json" | wc -l)"
[ "$rows" -eq "$runs" ] && [ "$rows" -gt 0 ] ||
  { echo "fem-tables: $rows moving rows for $runs moving runs in the JSON"; exit 1; }
grep -qE '^\| R0 \| [0-9.]+–[0-9.]+ \| [0-9.]+ \| [0-9.]+ / [0-9.]+ ' <<< "$out" ||
  { echo "fem-tables: no off-grid row R0"; exit 1; }
echo '{"bench": "other"}' > "$json.bad"
if err="$("$root/tools/fem-tables" "$json.bad" 2>&1)"; then echo "fem-tables took a JSON without the bench's fields"; exit 1; fi
grep -q "$json.bad: no field" <<< "$err" || { echo "fem-tables: unclear refusal: $err"; exit 1; }
echo "fem tables: ok ($rows moving rows, $accuracy accuracy rows)"
