#!/usr/bin/env bash
# Accelerator bench, one prepared run (< 9.5 min wall): the screening engine at 5,000
# routes, the constellation day's planner stages, and the bound's DP (numpy vs JAX on the
# default device, one value vector and a batch of them).
#
#   OUT=/some/dir bash scripts/gpu_bench.sh          # from the repository root
#
# Device-agnostic: JAX runs on whatever jax.devices() gives (a GPU when JAX's CUDA plugin
# is installed, else the CPU); devices.txt records it. Each section has its own time cap
# (a section cut by its cap writes no JSON; the others still do). Only the JSON files and
# logs land in $OUT; copy them to bench/results/gpu/ and render the tables with
#   python -m bench --render --out bench/results/gpu
set -uo pipefail
OUT="${OUT:-bench/results/gpu}"
WORK="$(mktemp -d)"
mkdir -p "$OUT"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1
PY="${PY:-python3}"
{
  date -u +%FT%TZ
  "$PY" -c "import jax; print('jax', jax.__version__); print(jax.devices())"
  nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv 2>/dev/null || true
  nproc
} > "$OUT/devices.txt" 2>&1
cat "$OUT/devices.txt"
# Sections in the order of what the device time is for; each has its own cap and
# together they stay under 9 min. On 2 CPU cores section 1 takes 141 s and section 3
# ~40 s; section 2 is a whole plan bounded by its time limit.
# 1. the screening engine at 5,000 routes, feasible rows only (speed against the same-run
#    ceiling and the host path, memory, streaming), in the device's chunk
#    (jaxspline.screen.default_chunk_size)
timeout 240 "$PY" -m bench --section screening --routes 5000 --modes feasible --reps 2 \
  --out "$WORK/s" 2>&1 | tee "$OUT/screening.log"
echo "screening section exit ${PIPESTATUS[0]}"
cp "$WORK/s/screening.json" "$OUT/" 2>/dev/null
# 2. the constellation day planned in 150 s (the least limit its 2-core run accepts is
#    ~133 s): stage times in scale.json, beside bench/results/SCALE.md's 2-core rows
timeout 220 "$PY" -m bench --section scale --sizes day:150 --out "$WORK/d" 2>&1 \
  | tee "$OUT/day.log"
echo "day stages exit ${PIPESTATUS[0]}"
cp "$WORK/d/scale.json" "$OUT/" 2>/dev/null
# 3. the bound's DP: the 12x12h preset cut to 0.5 h (problem build + rates + bounds)
timeout 60 "$PY" -m bench --section bound --bound-hours 0.5 --bound-seconds 2 \
  --out "$WORK/b" 2>&1 | tee "$OUT/bound.log"
echo "bound section exit ${PIPESTATUS[0]}"
cp "$WORK/b/bound.json" "$OUT/" 2>/dev/null
ls -la "$OUT"
