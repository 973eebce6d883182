#!/usr/bin/env bash
# On a machine with an NVIDIA GPU (and the build folder beside the sources): the whole test
# suite, compute-sanitizer on a small run of every CUDA kernel, the CUDA and GL benchmarks
# and the GPU experiments (Tables 2 and 3, tiles; hybrid ones when built). Logs and results
# go into $1 (default gpu-check/); a short table is printed last.
# Environment: PARTS (which of "tests sanitizers bench experiments scale" to run, default all
# but scale),
# BUILD (build folder, default build/default), MAX_SIZE (largest experiment grid,
# default 4096), EXPERIMENTS (default "table2 table3 tiles interop swap"), JOBS (ctest -j, default 4),
# BASE_BENCH (a deformlab-bench of an earlier build: its cuda and gl rows are measured beside
# this build's in the same session, for an A/B comparison).
# The build folder can travel as .dev/build.tgz (scripts/pack-for-device.sh), unpacked here.
set -uo pipefail
cd "$(dirname "$0")/.."
for t in .dev/*.tgz; do [ -f "$t" ] && tar -xzf "$t"; done
build=${BUILD:-build/default}
out=${1:-gpu-check}
max=${MAX_SIZE:-4096}
mkdir -p "$out/results"
summary=()
parts=${PARTS:-tests sanitizers bench experiments}
app="$build/app/deformlab"
part() { [[ " $parts " == *" $1 "* ]]; }

if part tests; then
  ctest --test-dir "$build" -j"${JOBS:-4}" --output-on-failure >"$out/ctest.log" 2>&1
  summary+=("ctest: $(grep -E 'tests passed|tests failed' "$out/ctest.log" | tail -1)")
  grep -E "Label|^ *(unit|match|gl|cuda|interop) *=" "$out/ctest.log" >>"$out/ctest-labels.txt"
fi

cuda_tests="$build/tests/cuda/deformlab_cuda_tests"
match_tests="$build/tests/match/deformlab_match_tests"
if part sanitizers && [ -x "$cuda_tests" ] && command -v compute-sanitizer >/dev/null; then
  for tool in memcheck racecheck synccheck initcheck; do
    {
      compute-sanitizer --tool "$tool" "$match_tests" --gtest_filter='*/cuda_*cloth37x53*:*/cuda_*lattice6x5x4*'
      compute-sanitizer --tool "$tool" "$cuda_tests" --gtest_filter='CudaConstraints*:CudaPipeline.Energy*'
    } >"$out/sanitizer-$tool.log" 2>&1
    summary+=("$tool: $(grep -E 'ERROR SUMMARY|RACECHECK SUMMARY' "$out/sanitizer-$tool.log" | tr '\n' ' ')")
  done
fi

bench="$build/bench/deformlab-bench"
bench_pair() {  # name, then the bench arguments: this build's and (BASE_BENCH) the earlier build's rows
  local name=$1; shift
  "$bench" "$@" --csv "$out/bench-$name.csv" >"$out/bench-$name.txt" 2>&1
  if [ -n "${BASE_BENCH:-}" ]; then "$BASE_BENCH" "$@" --csv "$out/bench-$name-base.csv" >"$out/bench-$name-base.txt" 2>&1; fi
}
if part bench; then
  bench_pair cuda cuda --sizes 256 1024 2048 4096
  bench_pair gl gl --sizes 256 1024 2048
  bench_pair hybrid hybrid --sizes 256 1024 --updates compute --modes map external-gpusync --no-baselines
fi

if part experiments; then
  "$app" calibrate --out "$out/results/calibration.json" >"$out/calibrate.txt" 2>&1
  for x in ${EXPERIMENTS-table2 table3 tiles interop swap}; do
    "$app" experiment "$x" --max-size "$max" --out "$out/results/$x" >"$out/experiment-$x.log" 2>&1
    summary+=("experiment $x: $(tail -2 "$out/experiment-$x.log" | head -1)")
  done
fi

# The largest grids: 20 steps with the stop rule checked every step (state.ply left out: 13 GB
# at 16384^2), device memory sampled by nvidia-smi, a frame of a 16384^2 cloth drawn from GL
# buffers and from a CUDA state; then --compare cpu at 1024^2 and 96^3.
scale_run() {  # name, then run arguments
  local name=$1; shift
  nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 100 >"$out/scale-$name.gpumem" 2>/dev/null &
  local smi=$!
  "$app" run --steps 20 --check-every 1 --no-state --out "/tmp/scale-$name" "$@" >"$out/scale-$name.log" 2>&1
  local rc=$?
  kill "$smi" 2>/dev/null
  cp "/tmp/scale-$name/manifest.json" "$out/scale-$name.json" 2>/dev/null
  for f in /tmp/scale-$name/frames/*.png; do [ -f "$f" ] && cp "$f" "$out/scale-$name-$(basename "$f")"; done
  rm -rf "/tmp/scale-$name"
  local peak=$(sort -n "$out/scale-$name.gpumem" | tail -1)
  summary+=("scale $name (rc $rc, GPU peak ${peak} MiB): $(grep -E 'median|memory:|error|refused|limit' "$out/scale-$name.log" | tr -s ' ' | tr '\n' ' ')")
}
if part scale; then
  for p in cuda-fused cuda-naive glsl-compute; do
    scale_run "$p-cloth16384" --pipeline "$p" --grid 16384x16384
    scale_run "$p-lattice512" --pipeline "$p" --lattice 512x512x512
  done
  scale_run glsl-tf-cloth11585 --pipeline glsl-tf --grid 11585x11585
  scale_run glsl-tf-lattice512 --pipeline glsl-tf --lattice 512x512x512
  scale_run glsl-tf-cloth16384 --pipeline glsl-tf --grid 16384x16384
  scale_run glsl-compute-frames16384 --pipeline glsl-compute --grid 16384x16384 --frames 20
  scale_run cuda-fused-frames16384 --pipeline cuda-fused --grid 16384x16384 --frames 20
  for p in cuda-fused cuda-naive glsl-compute glsl-tf; do
    scale_run "$p-compare1024" --pipeline "$p" --grid 1024x1024 --compare cpu
    scale_run "$p-compare96" --pipeline "$p" --lattice 96x96x96 --compare cpu
  done
fi

printf '%s\n' "${summary[@]}"
