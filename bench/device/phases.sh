#!/bin/bash
# Device check: where a GPU run's time goes (bench/phases.py: the transforms, the mode-grid arithmetic, the pairs'
# search and sums, the rest, each command on one thread so the clocks add up), and colour on the GPU (paired
# against the commit before issue 34 and the CPU path). On the lent machine, from the repository root, after
# bench/device/prepare.sh here (carry .gpu):
#     bash bench/device/phases.sh      (writes under $OUT; SPECS="backend:threads:M ..." adjusts it)
source bench/device/setup.sh

log tests
timeout ${T_TESTS:-120} $PY -m pytest -q -p no:cacheprovider tests/test_gpu.py tests/test_transforms.py \
  tests/test_objective.py tests/test_torus.py::test_backends_reach_the_same_energy > "$OUT/pytest.log" 2>&1
tail -3 "$OUT/pytest.log"

for spec in ${SPECS:-cufinufft:1:200000 ducc0:1:200000 cufinufft:1:1000000}; do
  IFS=: read -r backend threads count <<< "$spec"
  log "phases $backend threads $threads M $count"
  timeout ${T_PHASES:-200} $PY bench/phases.py .gpu/inputs/cat1024.png -M "$count" --backend "$backend" \
    --threads "$threads" --output "$OUT/phases-$backend-$threads-$count.json" 2>&1 | tee -a "$OUT/phases.log"
done

if [ -z "${SKIP_COLOUR:-}" ]; then
  log "paired colour"
  OLD="env PYTHONPATH=${S}:$R/.gpu/old $PY -P -m stipple"
  mkdir -p /tmp/paired && cp -r .gpu/inputs /tmp/paired/
  timeout ${T_PAIRED:-240} $PY bench/paired.py --old "$OLD" --new "$PY -m stipple" --variant "gpu=--backend cufinufft" \
    --cases colour --repeats 1 --out /tmp/paired --output "$OUT/paired-colour.json" 2>&1 | tee -a "$OUT/paired.log"
fi
log done
