#!/bin/bash
# Device check of the speed work: GPU backend tests, whole commands (old / new CPU / new GPU), per-iteration times.
# On the lent machine, from the repository root, after bench/device/prepare.sh here (carry .gpu):
#     bash bench/device/check.sh      (writes under $OUT; CASES, T_TESTS, T_PAIRED, T_RUN, ITERATIONS adjust it)
source bench/device/setup.sh

log tests
timeout ${T_TESTS:-120} $PY -m pytest -q -p no:cacheprovider tests/test_gpu.py tests/test_transforms.py \
  tests/test_objective.py tests/test_torus.py::test_backends_reach_the_same_energy > "$OUT/pytest.log" 2>&1
tail -3 "$OUT/pytest.log"

# -P: not the working directory (this checkout) first on the path, so the old package is the one imported.
OLD="env PYTHONPATH=${S}:$R/.gpu/old $PY -P -m stipple"
mkdir -p /tmp/paired && cp -r .gpu/inputs /tmp/paired/
# A case is NAME:REPEATS, or NAME:REPEATS:new for the new version alone (its old run timed in another call).
for spec in ${CASES:-million:1 portrait:2}; do
  IFS=: read -r name repeats which <<< "$spec"
  old=(--old "$OLD"); [ "${which:-}" = new ] && old=()
  log "paired $name"
  timeout ${T_PAIRED:-330} $PY bench/paired.py "${old[@]}" --new "$PY -m stipple" --variant "gpu=--backend cufinufft" \
    --cases "$name" --repeats "$repeats" --out /tmp/paired --output "$OUT/paired-$name.json" 2>&1 | tee -a "$OUT/paired.log"
done

log "per-iteration"
timeout ${T_RUN:-120} $PY bench/run.py --backends ducc0,cufinufft --sections torus --iterations ${ITERATIONS:-8} \
  ${RUN_EXTRA:-} --output "$OUT/run.json" > "$OUT/run.log" 2>&1
tail -4 "$OUT/run.log"
log done
