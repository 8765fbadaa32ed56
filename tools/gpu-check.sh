#!/usr/bin/env bash
# hemo's check on a real GPU: the GPU test suite with the validation layer (core checks and
# synchronization validation), the main job (the aneurysm scene), the main job's first steps
# under validation, and the benchmarks that judge speed. Writes one report, text and JSON,
# naming the device, the driver and the figures. See docs/gpu-check.md.
#
# usage: tools/gpu-check.sh [--build DIR] [--out DIR] [--device SEL] [--phases "P ..."]
#   --build DIR   a build tree of hemo (default: build/release)
#   --out DIR     where the report goes (default: out/gpu-check)
#   --device SEL  the Vulkan device: an index or part of its name (default: hemo's choice,
#                 discrete > integrated > virtual > CPU)
#   --phases      a subset of: device gtest aneurysm validated speed table1 render primitives
#                 scale scale_h2 scale_cells (default: all, in that order)
# Exit status: 0 when every phase passed, 1 otherwise (the report says which).
set -uo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=$root/build/release
out=$root/out/gpu-check
phases="device gtest aneurysm validated speed table1 render primitives scale scale_h2 scale_cells"
device=${HEMO_DEVICE:-}
while [ $# -gt 0 ]; do
  case $1 in
    --build) build=$(cd "$2" && pwd) || exit 1; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --device) device=$2; shift 2 ;;
    --phases) phases=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "gpu-check: unknown argument '$1' (see --help)" >&2; exit 1 ;;
  esac
done
for phase in $phases; do
  case $phase in
    device|gtest|aneurysm|validated|speed|table1|render|primitives|scale|scale_h2|scale_cells) ;;
    *) echo "gpu-check: unknown phase '$phase'" >&2; exit 1 ;;
  esac
done
for exe in tests/hemo_gpu_tests apps/hemo-run apps/hemo-bench; do
  if [ ! -x "$build/$exe" ]; then
    echo "gpu-check: $build/$exe is missing: build hemo first (make build, or cmake --build $build)" >&2
    exit 1
  fi
done
mkdir -p "$out" || exit 1
out=$(cd "$out" && pwd)
[ -n "$device" ] && export HEMO_DEVICE=$device
# Containers often carry the NVIDIA driver's Vulkan manifest outside the loader's search path.
if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ]; then
  for icd in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json; do
    [ -f "$icd" ] && export VK_DRIVER_FILES=$icd VK_ICD_FILENAMES=$icd
  done
fi

text=$out/report.txt
: > "$text"
say() { printf '%s\n' "$*" | tee -a "$text"; }
json_string() { printf '%s' "$1" | sed 's/\\/\\\\/g; s/"/\\"/g' | tr -d '\n'; }

# run NAME LIMIT_S JSON_FILE CMD...: runs one phase under a time limit, its output into the
# text report, and notes its exit status and seconds for the JSON report.
results=()
failed=0
run() {
  local name=$1 limit=$2 file=$3; shift 3
  say ""
  say "=== $name: $*"
  local start end rc
  start=$(date +%s.%N)
  timeout "$limit" "$@" > "$out/$name.log" 2>&1
  rc=$?
  end=$(date +%s.%N)
  local seconds
  seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')
  if [ "$name" = gtest ]; then
    grep -E '^\[  (FAILED|PASSED|SKIPPED) |^\[==========\]|Failure|validation (error|warning)' "$out/$name.log" | head -200 | tee -a "$text"
  else
    tail -n 60 "$out/$name.log" | tee -a "$text"
  fi
  [ "$rc" = 124 ] && say "(stopped after its limit of $limit s)"
  say "=== $name: exit $rc, $seconds s"
  [ "$rc" != 0 ] && failed=1
  local result=null
  [ -n "$file" ] && [ -s "$file" ] && result=$(cat "$file")
  results+=("{\"phase\": \"$name\", \"exit\": $rc, \"seconds\": $seconds, \"result\": $result}")
}

say "hemo GPU check, $(date -u +%Y-%m-%dT%H:%M:%SZ), commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
say "host: $(uname -srm); build: $build"
command -v nvidia-smi > /dev/null && nvidia-smi -L 2>/dev/null | tee -a "$text"

cd "$root" || exit 1
for phase in $phases; do
  case $phase in
    device) run device 60 "$out/device.json" "$build/apps/hemo-bench" device --json "$out/device.json" ;;
    gtest)
      # The suite turns on the validation layer itself (core and synchronization checks).
      run gtest 1800 "" "$build/tests/hemo_gpu_tests" --gtest_output=xml:"$out/gtest.xml" ;;
    aneurysm) run aneurysm 600 "$out/aneurysm/summary.json" "$build/apps/hemo-run" scenes/aneurysm.json --out "$out/aneurysm" ;;
    validated)
      # The main job's path through hemo-run (the surface and PNG frames included) under the
      # validation layer's core and synchronization checks: a message fails it (exit 3).
      run validated 600 "$out/validated/summary.json" env HEMO_VALIDATION=1 "$build/apps/hemo-run" scenes/aneurysm.json \
        --steps 200 --surface-every 100 --png-every 100 --png-size 320x240 --out "$out/validated" ;;
    speed) run speed 600 "$out/speed.json" "$build/apps/hemo-bench" speed --repeat 3 --json "$out/speed.json" ;;
    table1) run table1 600 "$out/table1.json" "$build/apps/hemo-bench" table1 --json "$out/table1.json" ;;
    render) run render 600 "$out/render.json" "$build/apps/hemo-bench" render --json "$out/render.json" ;;
    primitives) run primitives 600 "$out/primitives.json" "$build/apps/hemo-bench" primitives --json "$out/primitives.json" ;;
    # The 3D dam break from 0.1M particles up to what the device holds, at h/dp 1.3 and 2.
    scale) run scale 900 "$out/scale.json" "$build/apps/hemo-bench" scale --json "$out/scale.json" ;;
    scale_h2) run scale_h2 900 "$out/scale_h2.json" "$build/apps/hemo-bench" scale --smoothing-ratio 2 --json "$out/scale_h2.json" ;;
    scale_cells) run scale_cells 900 "$out/scale_cells.json" "$build/apps/hemo-bench" scale --neighbour-search cells --max-particles 16000000 --json "$out/scale_cells.json" ;;
  esac
done

# The gtest totals from its XML report.
gtest_json=null
if [ -s "$out/gtest.xml" ]; then
  tests=$(grep -o '<testsuites [^>]*' "$out/gtest.xml" | grep -o ' tests="[0-9]*"' | grep -o '[0-9]*')
  failures=$(grep -o '<testsuites [^>]*' "$out/gtest.xml" | grep -o ' failures="[0-9]*"' | grep -o '[0-9]*')
  # the failed tests as the summary at the end of the log lists them
  names=$(grep -E '^\[  FAILED  \] [^ ]' "$out/gtest.log" | grep -v ' ms)$\|listed below' |
          sed 's/^\[  FAILED  \] \([^, ]*\).*/"\1"/' | sort -u | paste -sd, -)
  gtest_json="{\"tests\": ${tests:-0}, \"failures\": ${failures:-0}, \"failed\": [${names}]}"
  say ""
  say "gtest: ${tests:-?} tests, ${failures:-?} failed"
fi

{
  printf '{\n  "tool": "tools/gpu-check.sh",\n'
  printf '  "commit": "%s",\n' "$(git -C "$root" rev-parse HEAD 2>/dev/null || echo unknown)"
  printf '  "host": "%s",\n' "$(json_string "$(uname -srm)")"
  printf '  "passed": %s,\n' "$([ $failed = 0 ] && echo true || echo false)"
  printf '  "gtest": %s,\n' "$gtest_json"
  printf '  "phases": [\n'
  for i in "${!results[@]}"; do
    [ "$i" -gt 0 ] && printf ',\n'
    printf '    %s' "${results[$i]}"
  done
  printf '\n  ]\n}\n'
} > "$out/report.json"
say ""
say "report: $out/report.txt and $out/report.json ($([ $failed = 0 ] && echo 'every phase passed' || echo 'a phase FAILED'))"
exit $failed
