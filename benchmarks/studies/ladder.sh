#!/usr/bin/env bash
# The ladder study (docs/ladder.md) on the benchmark runner, from the repository's root:
#   bash benchmarks/studies/ladder.sh [OUT]                  steps 1-5 (OUT defaults to ./ladder-out)
#   bash benchmarks/studies/ladder.sh OUT --test RUN_DIR     step 6, with the run folder chosen in step 5
# A set encoder trained on 1-4 objects, measured on objects-1 .. objects-12. Steps: expert
# demonstrations on objects-1-4; BC (two recipes) and DAgger; copies acting with the episode
# rules; the choice among them on objects-v2:dev; the chosen one on objects-v2:test. One
# worker throughout; the benchmark runs the expert and random policies as references.
set -euo pipefail
OUT=${1:-ladder-out}

# 6. The chosen recipe on the test part: scenarios no recipe was chosen on.
if [[ "${2:-}" == "--test" ]]; then
    python -m training.cli benchmark --split objects-v2:test --out "$OUT/test" --policies greedy "$3"
    python -m benchmarks.studies.ladder goals "$OUT/test/results.json"
    exit 0
fi
export MINARI_DATASETS_PATH=${MINARI_DATASETS_PATH:-$PWD/$OUT/datasets}
DATASET=fetchcarry/ladder-objects-1-4-expert-v0
R="$OUT/runs"
RULES="skip_delivered=true push_after_approach=true avoid_returns=true"

# 1. 300 expert episodes, k uniform in 1..4, seeds 0..299, in candidate phases.
python -m training.cli generate --family objects-1-4 --interface phases --episodes 300 --seed 0 \
    --dataset-id "$DATASET" --workers 1

# 2. The set encoder with BC, two recipes (20 and 60 epochs), training seed 0.
for EPOCHS in 20 60; do
    python -m training.cli train bc --dataset "$DATASET" --encoder set --epochs "$EPOCHS" --seed 0 \
        --out "$R/bc-set-e$EPOCHS-s0"
done

# 3. DAgger, set encoder, one iteration: iteration 0 is BC on the same demonstrations, then
#    learner episodes on objects-2/3/4 labelled by the expert (1-4 objects only).
python -m training.cli train dagger --family objects-1-4 --dataset "$DATASET" --demonstrations 300 \
    --iterations 1 --episodes-per-iteration 40 --learner-families objects-2,objects-3,objects-4 \
    --eval-episodes 10 --epochs 20 --encoder set --seed 0 --workers 1 --out "$R/dagger-set-i1-s0"

# 4. The episode rules (no weight changes): copies of the 20-epoch BC run and of the DAgger run.
# shellcheck disable=SC2086  # RULES is three words on purpose
python -m benchmarks.studies.ladder variant "$R/bc-set-e20-s0" "$R/bc-set-e20-s0-rules" $RULES
# shellcheck disable=SC2086
python -m benchmarks.studies.ladder variant "$R/dagger-set-i1-s0" "$R/dagger-set-i1-s0-rules" $RULES

# 5. The choice on the development part of the objects split (objects-1 .. objects-12 in turn).
python -m training.cli benchmark --split objects-v2:dev --out "$OUT/dev" --policies greedy \
    "$R/bc-set-e20-s0" "$R/bc-set-e60-s0" "$R/dagger-set-i1-s0" "$R/bc-set-e20-s0-rules" "$R/dagger-set-i1-s0-rules"
python -m benchmarks.studies.ladder goals "$OUT/dev/results.json"

