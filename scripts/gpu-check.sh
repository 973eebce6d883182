#!/usr/bin/env bash
# On a machine with an NVIDIA GPU (and the build folder beside the sources): the whole test
# suite, compute-sanitizer on a small run of every CUDA kernel, the CUDA and GL benchmarks
# and the GPU experiments (Tables 2 and 3, tiles; hybrid ones when built). Logs and results
# go into $1 (default gpu-check/); a short table is printed last.
# Environment: PARTS (which of "tests sanitizers bench experiments timing mesh scale endurance speed profile"
# to run, default all but timing, mesh, scale, endurance, speed and profile),
# BUILD (build folder, default build/default), MAX_SIZE (largest experiment grid; mesh sweeps take none,
# default 4096), EXPERIMENTS (default "table2 table3 tiles interop swap"), JOBS (ctest -j, default 4),
# LABELS (the tests part's ctest -L regex, default every label), SANITIZERS and MATCH_SHARDS (the
# sanitizers part's tools and how many shards its match set runs in), ARCHIVE (see the end),
# BASE_BENCH (a deformlab-bench of an earlier build: its cuda and gl rows are measured beside
# this build's in the same session, for an A/B comparison), BASE_APP (its deformlab: the
# timing part's experiment cells again).
# On the H100 the parts took (build 8f91918): tests 5.3 min (JOBS=8), sanitizers 8.6, mesh about
# 3.5 (28 runs, each loading a 1 M-node mesh and warming up for a second); timing and mesh
# together passed 10 minutes, so run them as separate commands where one is limited to that.
# On 2c35002: tests 6.4 min (JOBS=10); sanitizers with SANITIZERS="racecheck synccheck" 6.5 (its
# longest job racecheck on the CUDA tests, 388 s, 225 of them on CUDA-temporal's exact-match
# test), with "memcheck initcheck" 0.8. On 5d04c62 EXPERIMENTS=hybrid-meshes took 9.9 minutes in
# one call, on a machine just started (its Gmsh meshes generated anew each call), and 6.2 in an
# earlier call of the same experiment: run it alone.
# On b1c55d7 (its bench warming each case up for a second) timing ran past 9.5 minutes: its bench
# spent 3.6 of them on 8192^2 cuda-temporal cases, now left out, and glsl-tf's check runs 4.4 on
# 2000 steps each, now 200: on dbe6930 it took 3.5 minutes, and the tests part (JOBS=8) 5.3.
# The build folder can travel as .dev/*.tar.xz (scripts/pack-for-device.sh: the tree and its
# programs), unpacked here.
set -uo pipefail
cd "$(dirname "$0")/.."
for t in .dev/*.tar.xz; do [ -f "$t" ] && xz -dc "$t" | tar -xf -; done
build=${BUILD:-build/default}
out=${1:-gpu-check}
max=${MAX_SIZE:-4096}
mkdir -p "$out/results"
summary=()
parts=${PARTS:-tests sanitizers bench experiments}
app="$build/app/deformlab"
part() { [[ " $parts " == *" $1 "* ]]; }

# The tests part refuses to start when a program its tests run is not here (a .dev archive not
# carried; ctest then lists such a test without a command): the gl, viewer and cli tests also
# start deformlab itself.
if part tests; then
  missing=()
  while IFS='|' read -r prog name; do
    [ -z "$prog" ] && missing+=("the program of $name")
    case $prog in *_gl_tests | *_viewer_tests | *_cli_tests) [ -x "$app" ] || missing+=("$app") ;; esac
  done < <(ctest --test-dir "$build" ${LABELS:+-L "$LABELS"} --show-only=json-v1 | awk '
    /^    \{/ { prog = "" }
    /^      "command" :/ { getline; getline; prog = $0; sub(/^ *"/, "", prog); sub(/",?$/, "", prog) }
    /^      "name" :/ { name = $0; sub(/^ *"name" : "/, "", name); sub(/",?$/, "", name); print prog "|" name }')
  if [ ${#missing[@]} -gt 0 ]; then
    echo "gpu-check: the tests part needs what is not here: $(printf '%s\n' "${missing[@]}" | sort -u | head -3 |
      paste -sd ';' | sed 's/;/; /g') (carry .dev/programs.tar.xz: scripts/pack-for-device.sh)" >&2
    exit 2
  fi
  # A GPU stage unavailable here fails its test rather than skipping it (tests/support/gpu_required.hpp).
  DEFORMLAB_REQUIRE_GPU=1 ctest --test-dir "$build" -j"${JOBS:-4}" ${LABELS:+-L "$LABELS"} --output-on-failure \
    >"$out/ctest.log" 2>&1
  summary+=("ctest: $(grep -E 'tests passed|tests failed' "$out/ctest.log" | tail -1);" \
    "$(grep -c '(Skipped)' "$out/ctest.log") skipped (list in ctest.log)")
  grep -E "Label|^ *(unit|match|gl|cuda|interop|viewer) *=" "$out/ctest.log" >>"$out/ctest-labels.txt"
fi

cuda_tests="$build/tests/cuda/deformlab_cuda_tests"
match_tests="$build/tests/match/deformlab_match_tests"
bench="$build/bench/deformlab-bench"
# The four tools run side by side, each on its sets at once (the CUDA tests, the bench's own
# kernel beside the fused rows, the match tests in MATCH_SHARDS gtest shards, default 4), so that
# the part fits a 10-minute limit on one command. On the H100, the match set unsharded: all twelve
# at once took 6 min 49 s on 8f91918; on 35dedc8 they ran past 10 minutes, racecheck's match set
# alone 595 s for 149 of its 187 tests (cuda-temporal's and cuda-tiled's RK4 cases 8-14 s each
# under racecheck), memcheck's 374 s and synccheck's 300 s. SANITIZERS names the tools to run
# (default "memcheck racecheck synccheck initcheck").
if part sanitizers && [ -x "$cuda_tests" ] && command -v compute-sanitizer >/dev/null; then
  read -ra tools <<<"${SANITIZERS:-memcheck racecheck synccheck initcheck}"
  for tool in "${tools[@]}"; do
    compute-sanitizer --tool "$tool" "$cuda_tests" \
      --gtest_filter='CudaConstraints*:CudaPipeline.MaxDisplacement*:CudaTemporal*' \
      >"$out/sanitizer-$tool-cuda.log" 2>&1 &
    if [ -x "$bench" ]; then
      compute-sanitizer --tool "$tool" "$bench" cuda --sizes 64 --variants fused --tiles 16x8 --tile-size 64 \
        --graph-sizes 64 --temporal-sizes 64 --steps-per-launch 1 --warmup-ms 0 \
        >"$out/sanitizer-$tool-bench.log" 2>&1 &
    fi
    shards=${MATCH_SHARDS:-4}
    for ((i = 0; i < shards; ++i)); do
      GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i compute-sanitizer --tool "$tool" "$match_tests" \
        --gtest_filter='*/cuda_*cloth37x53*:*/cuda_fused_*cloth32:*/cuda_fused_*cloth32_math_fast:*/cuda_fused_*_tma_*:*/cuda_fused_*contact37x53_math_fast:*/cuda_*lattice6x5x4*:*/cuda_*surface30x20*:*/cuda_*volume8x6x5*:*LiveChanges*/cuda_*:*StepBack*/cuda_*' \
        >"$out/sanitizer-$tool-match-$i.log" 2>&1 &
    done
  done
  wait
  for tool in "${tools[@]}"; do
    logs=("$out/sanitizer-$tool"-*.log)
    summary+=("$tool: $(cat "${logs[@]}" | grep -cF '[       OK ]') of $(cat "${logs[@]}" | grep -c '^\[ RUN') tests passed; $(cat "${logs[@]}" |
      grep -E 'ERROR SUMMARY|RACECHECK SUMMARY' | sort | uniq -c | tr -s ' ' | tr '\n' ' ')")
  done
fi

bench_pair() {  # name, then the bench arguments: this build's and (BASE_BENCH) the earlier build's rows
  local name=$1; shift
  "$bench" "$@" --csv "$out/bench-$name.csv" >"$out/bench-$name.txt" 2>&1
  if [ -n "${BASE_BENCH:-}" ]; then "$BASE_BENCH" "$@" --csv "$out/bench-$name-base.csv" >"$out/bench-$name-base.txt" 2>&1; fi
}
if part bench; then
  bench_pair cuda cuda --sizes 256 1024 2048 4096
  bench_pair gl gl --sizes 256 1024 2048
  bench_pair hybrid hybrid --sizes 256 1024 --updates compute --modes map external-gpusync --no-baselines
  bench_pair draw draw --sizes 256 1024 2048 4096
fi

# The roofline work: cuda-fused in exact and fast math and cuda-temporal's steps per launch
# (bench), and cuda-temporal timed by run, by its experiment cell and by the bench.
if part speed; then
  "$bench" cuda --sizes 2048 --variants fused --integrator explicit-euler --graph-sizes 64 --tiles 16x8 32x8 32x16 64x4 \
    --temporal-sizes 2048 8192 --csv "$out/speed-bench.csv" >"$out/speed-bench.txt" 2>&1
  "$app" run --experiment table2 --grid 2048x2048 --pipeline cuda-temporal --integrator semi-implicit-euler \
    --steps 400 --check-every 4 --no-state --out /tmp/speed-run >"$out/speed-run-temporal.txt" 2>&1
  summary+=("speed: $(grep -A200 '^\[temporal\]' "$out/speed-bench.txt" | grep -E '^ *2048\^2 *semi-implicit' | tr -s ' ' | head -10 | tr '\n' ';')")
fi

# Nsight Compute on table2's scene at 2048^2 (its default clock control: the SM clock locked at
# base): cuda-fused in both maths and its three one-pass integrators, cuda-temporal, the bare
# gather (the bench's, each of its kernels at its 21st launch), and the force passes of
# cuda-naive and cuda-tiled.
# Beside the sections, the counts behind the bounds in docs/speed.md: warp instructions (at most
# one a scheduler and cycle) and L1 data-pipe wavefronts (at most one an SM and cycle). The
# programs' own output is dropped: their timings under the profiler are not the kernels'.
if part profile && command -v ncu >/dev/null; then
  sections=(--section SpeedOfLight --section MemoryWorkloadAnalysis --section ComputeWorkloadAnalysis
    --section InstructionStats --section WarpStateStats --section Occupancy --section LaunchStats
    --metrics smsp__inst_executed.sum,l1tex__data_pipe_lsu_wavefronts.sum,l1tex__data_pipe_lsu_wavefronts.avg.pct_of_peak_sustained_elapsed,l1tex__m_xbar2l1tex_read_bytes.sum,dram__bytes_read.sum,dram__bytes_write.sum)
  profile_run() {  # file name, kernel regex, then deformlab run's arguments (at least 21 launches of the kernel)
    local name=$1 kernel=$2; shift 2
    ncu --log-file "$out/ncu-$name.txt" --kernel-id "::regex:$kernel:21" "${sections[@]}" "$app" run \
      --experiment table2 --grid 2048x2048 --no-state --out /tmp/ncu-run "$@" >/dev/null 2>&1
  }
  for math in exact fast; do
    for integ in explicit-euler semi-implicit-euler verlet; do
      profile_run "fused-$integ-$math" fused_ --pipeline cuda-fused --integrator "$integ" --option math=$math --steps 30
    done
  done
  profile_run "fused-explicit-euler-exact-tma-off" fused_grid --pipeline cuda-fused --integrator explicit-euler \
    --option math=exact --option tma=off --steps 30
  for math in exact fast; do
    profile_run "temporal-$math" temporal_grid --pipeline cuda-temporal --integrator semi-implicit-euler \
      --option math=$math --steps 60 --check-every 4
  done
  for p in cuda-naive cuda-tiled; do
    profile_run "$p-force" force_grid --pipeline $p --integrator explicit-euler --option math=exact --steps 30
  done
  ncu --log-file "$out/ncu-bare-gather.txt" --kernel-name-base demangled --kernel-id "::regex:bare_gather:21" \
    "${sections[@]}" "$bench" cuda --sizes 2048 --variants fused --tiles 32x8 --tile-size 2048 --graph-sizes 64 \
    --temporal-sizes 0 >/dev/null 2>&1
  summary+=("profile: $(cat "$out"/ncu-*.txt | grep -c 'smsp__inst_executed.sum') kernels profiled ($out/ncu-*.txt)")
fi

if part experiments; then
  "$app" calibrate --out "$out/results/calibration.json" >"$out/calibrate.txt" 2>&1
  for x in ${EXPERIMENTS-table2 table3 tiles interop swap}; do
    sizes=(--max-size "$max")
    grep -qs '"models"' "experiments/$x.json" && sizes=()  # a mesh sweep has models, not grid sizes
    "$app" experiment "$x" "${sizes[@]}" --out "$out/results/$x" >"$out/experiment-$x.log" 2>&1
    summary+=("experiment $x: $(tail -2 "$out/experiment-$x.log" | head -1)")
  done
fi

# One scene timed three ways (table2's scene at 2048^2, explicit Euler): `deformlab run`, its
# experiment cell and deformlab-bench; then runs checking the stop rule every step against
# runs checking it once (the run's host wall time).
median_of() { grep -o "\"$1\": [0-9.e+-]*" "$2" | head -1 | awk '{ print $2 }'; }
if part timing; then
  # One scene (Table 2's, 2048^2, explicit Euler) timed three ways in exact and fast math: a run of
  # 2000 steps (glsl-tf and hybrid, about 20 ms a step: 200), its experiment cell and the bench's
  # row; each with the median SM clock the GPU ran it at.
  cat >"$out/clock-check.json" <<'JSON'
{"name": "clock-check", "base": "table2", "integrator": "explicit-euler",
 "sweep": {"sizes": [2048], "pipelines": ["cuda-fused", "cuda-naive", "glsl-compute", "glsl-tf", "hybrid", "hybrid-compute"],
           "options": [{"math": "exact"}, {"math": "fast"}],
           "warmup": 10, "steps": 20, "repetitions": 7, "cell_limit_s": 60}}
JSON
  "$app" experiment "$out/clock-check.json" --out "$out/results/clock-check" >"$out/timing-experiment.log" 2>&1
  [ -n "${BASE_APP:-}" ] && "$BASE_APP" experiment "$out/clock-check.json" --out "$out/results/clock-check-base" \
    >"$out/timing-experiment-base.log" 2>&1
  "$bench" cuda --sizes 2048 --variants fused naive --integrator explicit-euler --graph-sizes 64 --tile-size 2048 \
    --tiles 16x8 --temporal-sizes 2048 --steps-per-launch 2 --csv "$out/timing-bench-cuda.csv" \
    >"$out/timing-bench-cuda.txt" 2>&1
  "$bench" gl --sizes 2048 --integrator explicit-euler --csv "$out/timing-bench-gl.csv" >"$out/timing-bench-gl.txt" 2>&1
  "$bench" hybrid --sizes 2048 --integrator explicit-euler --modes map external-gpusync --no-baselines \
    --csv "$out/timing-bench-hybrid.csv" >"$out/timing-bench-hybrid.txt" 2>&1
  # The bench's row of each: cuda [steps] (exact) and [fused] (paper scene, fast); gl by name;
  # the hybrids' in the interop mode their run chose (exact: the bench's hybrids take the
  # pipelines' defaults).
  bench_ms() {
    case $1/$2 in
      cuda-fused/exact | cuda-naive/exact) awk -F, -v v="${1#cuda-}" '$1 == "steps" && $5 == v { print $11 " @" $15 }' "$out/timing-bench-cuda.csv" ;;
      cuda-fused/fast) awk -F, '$1 == "fused" && $2 == "paper" && $6 == "explicit-euler" && $8 == "fast" { print $11 " @" $15 }' "$out/timing-bench-cuda.csv" ;;
      glsl-compute/exact | glsl-tf/exact) awk -F, -v w="$1" '$4 == w { print $5 " @" $8 }' "$out/timing-bench-gl.csv" ;;
      glsl-compute/fast) awk -F, '$4 == "glsl-compute-fast" { print $5 " @" $8 }' "$out/timing-bench-gl.csv" ;;
      hybrid/exact | hybrid-compute/exact)
        mode=$(grep -o '"interop": *"[a-z-]*"' "$out/timing-run-$1-$2.json" | head -1 | sed 's/.*"\([a-z-]*\)"$/\1/')
        awk -F, -v p="$1" -v m="$mode" '$2 == p && $3 == m { print $6 " @" $12 }' "$out/timing-bench-hybrid.csv" ;;
      *) echo - ;;
    esac
  }
  for pm in cuda-fused/exact cuda-fused/fast cuda-naive/exact cuda-naive/fast glsl-compute/exact glsl-compute/fast \
    glsl-tf/exact glsl-tf/fast hybrid/exact hybrid-compute/exact hybrid-compute/fast; do
    p=${pm%/*} math=${pm#*/} steps=2000; [ "$p" = glsl-tf ] || [ "$p" = hybrid ] && steps=200
    "$app" run --experiment table2 --pipeline "$p" --option "math=$math" --grid 2048x2048 --steps "$steps" \
      --check-every 100000 --no-state --out "/tmp/timing-$p-$math" >"$out/timing-run-$p-$math.log" 2>&1
    cp "/tmp/timing-$p-$math/manifest.json" "$out/timing-run-$p-$math.json"
    cell=$(ls "$out"/results/clock-check/cells/"$p"__*"$math"* 2>/dev/null | head -1)
    summary+=("timing $p $math 2048^2 paper scene, ms/step @ median SM MHz: run $(median_of median_step_ms "$out/timing-run-$p-$math.json") @$(median_of sm_mhz_median "$out/timing-run-$p-$math.json"), cell $(median_of median_ms "$cell") @$(median_of sm_mhz_median "$cell"), bench $(bench_ms "$p" "$math")")
  done
  # Three runs each of 2000 steps (glsl-tf, 20 ms a step: 200); "/fast": math=fast; cuda-temporal
  # checks at each launch (2 steps).
  for pm in cuda-fused cuda-fused/fast cuda-temporal glsl-compute glsl-tf hybrid-compute; do
    p=${pm%/*}; opt=(); [ "$pm" != "$p" ] && opt=(--option math=fast)
    first=1; [ "$p" = cuda-temporal ] && first=2
    steps=2000; [ "$p" = glsl-tf ] && steps=200
    for every in $first $steps; do
      walls=""
      for rep in 1 2 3; do
        "$app" run --experiment table2 --pipeline "$p" "${opt[@]}" --grid 2048x2048 --steps "$steps" \
          --check-every "$every" --no-state --out "/tmp/check-$rep" >"$out/timing-check-${pm/\//-}-$every-$rep.log" 2>&1
        walls+=" $(median_of wall_ms /tmp/check-$rep/manifest.json)"
        rm -rf "/tmp/check-$rep"
      done
      summary+=("$pm 2048^2, stop rule every $every steps: wall ms of $steps steps:$walls")
    done
  done
fi

# Node order on a mesh: a 1024 x 1024 triangulated sheet (1 M nodes, written as OBJ here)
# in each order, 200 steps of the paper's drag scene on each GPU pipeline, the stop rule once;
# cuda-fused and glsl-compute also without the warm-up.
if part mesh; then
  python3 - "$out/sheet.obj" <<'PY'
import sys
n = 1024
with open(sys.argv[1], "w") as f:
    f.write("".join(f"v {i / (n - 1) - 0.5:.7f} 1 {j / (n - 1) - 0.5:.7f}\n" for j in range(n) for i in range(n)))
    f.write("".join(f"f {j*n+i+1} {(j+1)*n+i+1} {(j+1)*n+i+2}\nf {j*n+i+1} {(j+1)*n+i+2} {j*n+i+2}\n"
                    for j in range(n - 1) for i in range(n - 1)))
PY
  for order in file shuffled rcm morton; do
    cat >"$out/sheet-$order.json" <<JSON
{"model": {"type": "mesh", "file": "sheet.obj", "order": "$order", "pins": [{"nearest": [-0.5, 1, -0.5]}, {"nearest": [0.5, 1, -0.5]}]},
 "drag": {"node": {"nearest": [0, 1, 0]}, "path": [[0, 0, 0, 0], [1, 0, 0.3, 0]]}}
JSON
    # "-cold": without the run's warm-up (its first steps at the clock the GPU dropped to while
    # the mesh loaded); timings.csv kept for those runs and their warm counterparts.
    for p in cuda-fused cuda-naive cuda-tiled cuda-scatter glsl-compute cuda-fused-cold glsl-compute-cold; do
      warm=(); [ "${p%-cold}" != "$p" ] && warm=(--warmup-ms 0)
      "$app" run --scene "$out/sheet-$order.json" --pipeline "${p%-cold}" --steps 200 --check-every 100000 --no-state \
        "${warm[@]}" --out "/tmp/mesh-$order-$p" >"$out/mesh-$order-$p.log" 2>&1
      cp "/tmp/mesh-$order-$p/manifest.json" "$out/mesh-$order-$p.json" 2>/dev/null
      case $p in cuda-fused* | glsl-compute*) cp "/tmp/mesh-$order-$p/timings.csv" "$out/mesh-$order-$p.csv" ;; esac
      summary+=("mesh sheet 1M order $order $p: median $(median_of median_step_ms "$out/mesh-$order-$p.json") ms/step, bandwidth $(median_of bandwidth "$out/mesh-$order-$p.json")")
    done
  done
  rm -f "$out/sheet.obj"
fi

# The largest grids: 20 steps with the stop rule checked every step (state.ply left out: 13 GB
# at 16384^2), device memory sampled by nvidia-smi, a frame of a 16384^2 cloth drawn from GL
# buffers and from a CUDA state; then --compare reference at 1024^2 and 96^3.
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
  for suffix in "" -fast; do  # exact math (the default), then fast math
    math=(); [ -n "$suffix" ] && math=(--option math=fast)
    for p in cuda-fused cuda-naive glsl-compute; do
      scale_run "$p-cloth16384$suffix" --pipeline "$p" --grid 16384x16384 "${math[@]}"
      scale_run "$p-lattice512$suffix" --pipeline "$p" --lattice 512x512x512 "${math[@]}"
    done
    scale_run "glsl-tf-cloth11585$suffix" --pipeline glsl-tf --grid 11585x11585 "${math[@]}"
    scale_run "glsl-tf-lattice512$suffix" --pipeline glsl-tf --lattice 512x512x512 "${math[@]}"
  done
  scale_run glsl-tf-cloth16384 --pipeline glsl-tf --grid 16384x16384
  scale_run glsl-compute-frames16384 --pipeline glsl-compute --grid 16384x16384 --frames 20
  scale_run cuda-fused-frames16384 --pipeline cuda-fused --grid 16384x16384 --frames 20
  for p in cuda-fused cuda-naive glsl-compute glsl-tf; do
    scale_run "$p-compare1024" --pipeline "$p" --grid 1024x1024 --compare reference
    scale_run "$p-compare96" --pipeline "$p" --lattice 96x96x96 --compare reference
  done
fi

# 1 M steps of a 1024^2 cloth on cuda-fused (stop rule every 1000 steps): host resident memory
# and GPU memory sampled each second, ms per step per 100 k-step window (host clock over the
# window, which the checks drain); then cuda-scatter's spread: the same 200 steps three times,
# the largest difference between the final states' values.
ply_floats() {  # the vertex values of a state.ply, one per line
  local off n
  off=$(grep -abo end_header "$1" | head -1 | cut -d: -f1)
  n=$(grep -a -m1 '^element vertex' "$1" | cut -d' ' -f3)
  tail -c +$((off + 12)) "$1" | head -c $((n * 24)) | od -An -v -tf4 | tr -s ' ' '\n' | grep -v '^$'
}
if part endurance; then
  nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 1000 >"$out/endurance.gpumem" 2>/dev/null &
  smi=$!
  (while sleep 1; do ps -o rss= -C deformlab; done) >"$out/endurance.rss" 2>/dev/null &
  rss=$!
  "$app" run --pipeline cuda-fused --grid 1024x1024 --steps 1000000 --check-every 1000 --no-state \
    --out /tmp/endurance >"$out/endurance.log" 2>&1
  kill "$smi" "$rss" 2>/dev/null
  awk -F, 'NR > 1 { w = int(($1 - 1) / 100000); s[w] += $3; n[w]++ }
           END { for (k = 0; k in n; k++) printf "%d-%dk: %.5f ms/step\n", k * 100, (k + 1) * 100, s[k] / n[k] }' \
    /tmp/endurance/timings.csv >"$out/endurance-windows.txt"
  summary+=("endurance: $(grep -E 'steps:' "$out/endurance.log" | tr -s ' ') windows: $(tr '\n' ';' <"$out/endurance-windows.txt")")
  summary+=("endurance memory: host RSS kB first/last/max $(head -1 "$out/endurance.rss")/$(tail -1 "$out/endurance.rss")/$(sort -n "$out/endurance.rss" | tail -1); GPU MiB first/last/max $(head -1 "$out/endurance.gpumem")/$(tail -1 "$out/endurance.gpumem")/$(sort -n "$out/endurance.gpumem" | tail -1)")
  for k in 1 2 3; do
    "$app" run --pipeline cuda-scatter --grid 512x512 --steps 200 --out "/tmp/scatter$k" >/dev/null 2>&1
    ply_floats "/tmp/scatter$k/state.ply" >"/tmp/scatter$k.txt"
  done
  for k in 2 3; do
    summary+=("scatter spread, run 1 vs $k (x y z m, vx vy vz m/s; largest |difference| over 512^2 nodes after 200 steps): $(paste /tmp/scatter1.txt /tmp/scatter$k.txt | awk '{ d = $1 - $2; if (d < 0) d = -d; if (d > m) m = d; if ($1 != $2) c++ } END { printf "%.3g, %d of %d values differ", m, c, NR }')")
  done
fi

# ARCHIVE=1: the results folder (experiment cells, reports, plots, frames: hundreds of files)
# as one archive, results.tar.xz, for a transfer that carries few files.
if [ -n "${ARCHIVE:-}" ] && [ -d "$out/results" ]; then
  tar -cJf "$out/results.tar.xz" -C "$out" results && rm -rf "$out/results"
fi

printf '%s\n' "${summary[@]}"
