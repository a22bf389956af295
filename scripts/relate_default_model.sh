#!/usr/bin/env bash
# Learn how a shipped model's vehicle drives its thrusters for the motion (auvdiag relate)
# from simulated normal missions: every mission scenario with seeds 1-3 to learn from and
# seed 101 held out to set the thresholds (build_default_model.sh's seeds; train itself
# learns the relation when a model is rebuilt).
# Usage: scripts/relate_default_model.sh [PROFILE] [MODEL_DIR] [FORMAT]   (as build_default_model.sh)
set -euo pipefail
source "$(dirname "$0")/model_arguments.sh"
learn=() holdout=()
for scenario in paper-normal mission-ccw mission-large-cw mission-large-ccw mission-fast-cw \
                mission-fast-ccw mission-sprint-cw mission-sprint-ccw; do
  for seed in 1 2 3 101; do
    auvdiag simulate "$scenario" --profile "$profile" --format "$format" --seed "$seed" \
      --output "$work/$scenario-s$seed" >/dev/null
    if [[ $seed == 101 ]]; then holdout+=(--holdout "$work/$scenario-s$seed")
    else learn+=("$work/$scenario-s$seed"); fi
  done
done
auvdiag relate "${learn[@]}" "${holdout[@]}" --model "$model" --profile "$profile"
