#!/usr/bin/env bash
# One bounded libFuzzer run (CTest *_fuzz_run, label fuzz): TARGET for SECONDS from a copy of
# the committed seed corpus, in WORK (a build directory: the source tree is never written).
# A crash, leak, timeout or out-of-memory fails the run; its input is kept in WORK with lines
# saying how to reproduce it and where to commit it once fixed.
#
# Usage: run_fuzz.sh TARGET_BINARY CORPUS_DIR WORK_DIR SECONDS
set -u
target=$1 corpus=$2 work=$3 seconds=$4
name=$(basename "$target")
[ -x "$target" ] || { echo "run_fuzz: $target: not built" >&2; exit 1; }
[ -d "$corpus" ] || { echo "run_fuzz: $corpus: no seed corpus" >&2; exit 1; }
# A fresh copy of the seeds each run: the inputs found go there, not into the repository.
rm -rf "$work/corpus"
mkdir -p "$work/corpus" "$work/artifacts"
cp "$corpus"/* "$work/corpus/"
marker="$work/.started"
touch "$marker"
"$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$work/corpus" >"$work/log.txt" 2>&1
status=$?
tail -n 8 "$work/log.txt"
if [ $status -ne 0 ]; then
  echo "run_fuzz: FAILED: $name exited $status (full log: $work/log.txt)"
  found=0
  for f in $(find "$work/artifacts" -type f -newer "$marker"); do
    found=1
    echo "run_fuzz: the failing input is kept: $f"
    echo "run_fuzz:   reproduce: $target $f"
    echo "run_fuzz:   once fixed, commit it as $corpus/regression_$(basename "$f")"
  done
  [ $found -eq 1 ] || echo "run_fuzz: no input was written (see the log)"
  exit 1
fi
echo "run_fuzz: $name: ${seconds} s without a failure ($(ls "$work/corpus" | wc -l) inputs in the working corpus)"
