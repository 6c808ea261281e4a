#!/usr/bin/env bash
# Accelerator bench, one prepared run (< 9.5 min wall): the bound's DP (numpy vs JAX on the
# default device, one value vector and a batch of them) and the screening engine.
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
# 1. the bound's DP: the 12x12h preset cut to 0.5 h and 3 h (problem build + rates + bounds)
timeout 100 "$PY" -m bench --section bound --bound-hours 0.5,3 --bound-seconds 2 \
  --out "$WORK/b" 2>&1 | tee "$OUT/bound.log"
echo "bound section exit ${PIPESTATUS[0]}"
cp "$WORK/b/bound.json" "$OUT/" 2>/dev/null
# 2. the screening engine, two sizes (speed, memory, streaming)
timeout 300 "$PY" -m bench --section screening --routes 1000 --routes 2000 --reps 3 \
  --out "$WORK/s" 2>&1 | tee "$OUT/screening.log"
echo "screening section exit ${PIPESTATUS[0]}"
cp "$WORK/s/screening.json" "$OUT/" 2>/dev/null
# 3. the bound's DP on the whole 12 h preset (its own JSON: bound12.json)
timeout 150 "$PY" -m bench --section bound --bound-hours 12 --bound-seconds 3 \
  --out "$WORK/b12" 2>&1 | tee "$OUT/bound12.log"
echo "bound 12 h exit ${PIPESTATUS[0]}"
cp "$WORK/b12/bound.json" "$OUT/bound12.json" 2>/dev/null
ls -la "$OUT"
