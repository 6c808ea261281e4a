#!/usr/bin/env bash
# Accelerator bench, one prepared run (< 6 min wall): the bound's DP (numpy vs JAX on the
# default device) and the screening engine, results into $OUT (default bench/results/gpu).
#
#   OUT=/some/dir bash scripts/gpu_bench.sh          # from the repository root
#
# Device-agnostic: JAX runs on whatever jax.devices() gives (a GPU when jax[cuda12] is
# installed, else the CPU); devices.txt records it. Each section has its own time cap
# (a section cut by its cap writes no JSON; the other still does). Copy $OUT to
# bench/results/gpu/ and render with: python -m bench --render --out bench/results/gpu
set -uo pipefail
OUT="${OUT:-bench/results/gpu}"
mkdir -p "$OUT"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
{
  date -u +%FT%TZ
  python -c "import jax; print('jax', jax.__version__); print(jax.devices())"
  nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv 2>/dev/null || true
  nproc
} > "$OUT/devices.txt" 2>&1
cat "$OUT/devices.txt"
# 1. the bound's DP: 12x12h preset cut to 0.5 h and 3 h (problem build + rates + bounds)
timeout 150 python -m bench --section bound --bound-hours 0.5,3 --bound-seconds 3 \
  --out "$OUT" 2>&1 | tee "$OUT/bound.log"
echo "bound section exit ${PIPESTATUS[0]}"
# 2. the screening engine, two sizes (speed, memory, streaming)
timeout 180 python -m bench --section screening --routes 1000 --routes 2000 --reps 3 \
  --out "$OUT" 2>&1 | tee "$OUT/screening.log"
echo "screening section exit ${PIPESTATUS[0]}"
ls -la "$OUT"
