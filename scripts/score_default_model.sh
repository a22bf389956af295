#!/usr/bin/env bash
# Measure a shipped model's skill (auvdiag score) on simulated normal dives it was not trained,
# held out or calibrated on (seed 301): the mission scenarios and every DMS before a mission.
# Usage: scripts/score_default_model.sh [PROFILE] [MODEL_DIR] [FORMAT]   (as build_default_model.sh)
set -euo pipefail
source "$(dirname "$0")/model_arguments.sh"
logs=()
for scenario in paper-normal mission-ccw mission-large-cw mission-sprint-ccw all-dms-and-mission; do
  auvdiag simulate "$scenario" --profile "$profile" --format "$format" --seed 301 \
    --output "$work/$scenario" >/dev/null
  logs+=("$work/$scenario")
done
auvdiag score "${logs[@]}" --model "$model" --profile "$profile"
