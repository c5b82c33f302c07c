#!/usr/bin/env bash
# Reproduces every figure of docs/ladder.md, from the repository's root:
#   bash scripts/ladder.sh [OUT]        (OUT defaults to ./ladder-out)
# Steps: expert demonstrations on objects-1-4, two BC recipes, the choice between them
# on development seeds of objects-5/6, then the curve on the test seeds (objects-1..8).
# One worker throughout; on a loaded 2-core machine it took about 1.5 h.
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
