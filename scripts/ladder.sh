#!/usr/bin/env bash
# Reproduces every figure of docs/ladder.md, from the repository's root:
#   bash scripts/ladder.sh [OUT]        (OUT defaults to ./ladder-out)
# Steps: expert demonstrations on objects-1-4, two BC recipes, the choice between them
# on development seeds of objects-5/6, then the curve on the test seeds (objects-1..8);
# then (steps 5-8) the acting rules, DAgger, the choice on development seeds of objects-5/6/8
# and the chosen recipes' curves. One worker throughout; on a loaded 2-core machine steps
# 1-4 took about 1.5 h, steps 5-8 about 1.5 h.
set -euo pipefail
OUT=${1:-ladder-out}
export MINARI_DATASETS_PATH=${MINARI_DATASETS_PATH:-$PWD/$OUT/datasets}
DATASET=fetchcarry/ladder-objects-1-4-expert-v0

# 1. 300 expert episodes, k uniform in 1..4, seeds 0..299, in candidate phases.
python -m training.cli generate --family objects-1-4 --interface phases --episodes 300 --seed 0 \
    --dataset-id "$DATASET" --workers 1

# 2. The set encoder with BC, two recipes (20 and 60 epochs), training seed 0.
for EPOCHS in 20 60; do
    python -m training.cli train bc --dataset "$DATASET" --encoder set --epochs "$EPOCHS" --seed 0 \
        --out "$OUT/runs/bc-set-e$EPOCHS-s0"
done

# 3. The choice: both recipes on 20 development seeds (from 100000) of objects-5 and objects-6.
python -m training.speed.ladder run --policies "$OUT/runs/bc-set-e20-s0" "$OUT/runs/bc-set-e60-s0" \
    --ks 5,6 --episodes 20 --seeds dev --out "$OUT/dev"

# 4. The curve: the chosen run, greedy and random-phases on 40 test seeds (from 1,090,000,000)
#    of objects-1..8, the expert on objects-1..4 for the cost ratio to the expert.
python -m training.speed.ladder run --policies "$OUT/runs/bc-set-e20-s0" greedy random-phases \
    --ks 1-8 --expert-ks 1-4 --episodes 40 --seeds test --out "$OUT/test"
python -m training.speed.ladder report "$OUT/test"

# 5. Acting rules on the 20-epoch network (no weight changes): skip_delivered, then with
#    push_after_approach and avoid_returns too.
R="$OUT/runs"
python -m training.speed.ladder variant "$R/bc-set-e20-s0" "$R/bc-set-e20-s0-sd" skip_delivered=true
python -m training.speed.ladder variant "$R/bc-set-e20-s0" "$R/bc-set-e20-s0-sd-pa-ar" \
    skip_delivered=true push_after_approach=true avoid_returns=true

# 6. DAgger, set encoder: iteration 0 is BC on the same 300 demonstrations (the same network as
#    bc-set-e20-s0), then learner episodes on objects-2/3/4 labelled by the expert (1-4 objects only).
#    The 2-iteration run's checkpoint after iteration 1 is what --iterations 1 computes.
#    (The run measured stopped there for that copy: variant takes an unfinished DAgger run's
#    last finished iteration.) Labels in the results: dagger-set-it1-s0-*, dagger-set-it2-s0-*.
for ITERATIONS in 1 2; do
    python -m training.cli train dagger --family objects-1-4 --dataset "$DATASET" --demonstrations 300 \
        --iterations "$ITERATIONS" --episodes-per-iteration 40 --learner-families objects-2,objects-3,objects-4 \
        --eval-episodes 10 --epochs 20 --encoder set --seed 0 --workers 1 --out "$R/dagger-set-i$ITERATIONS-s0"
    python -m training.speed.ladder variant "$R/dagger-set-i$ITERATIONS-s0" "$R/dagger-set-it$ITERATIONS-s0-sd-pa-ar" \
        skip_delivered=true push_after_approach=true avoid_returns=true
done
python -m training.speed.ladder variant "$R/dagger-set-i1-s0" "$R/dagger-set-it1-s0-sd" skip_delivered=true

# 7. The choice on development seeds: the first two on 20 seeds of objects-5/6, then 40 seeds of
#    objects-5/6/8 for the rest.
python -m training.speed.ladder run --policies "$R/bc-set-e20-s0-sd" --ks 5,6 --episodes 20 --seeds dev \
    --out "$OUT/dev-rules"
python -m training.speed.ladder run --policies "$R/bc-set-e20-s0-sd-pa-ar" "$R/dagger-set-it1-s0-sd" \
    "$R/dagger-set-it1-s0-sd-pa-ar" "$R/dagger-set-it2-s0-sd-pa-ar" --ks 5,6,8 --episodes 40 --seeds dev \
    --out "$OUT/dev-rules"
python -m training.speed.ladder report "$OUT/dev-rules"

# 8. The curves of the recipes reported, on the test seeds (greedy, random-phases and the expert of step 4).
python -m training.speed.ladder run --policies "$R/bc-set-e20-s0-sd-pa-ar" "$R/dagger-set-it1-s0-sd-pa-ar" \
    --ks 1-8 --episodes 40 --seeds test --out "$OUT/test"
python -m training.speed.ladder report "$OUT/test"
