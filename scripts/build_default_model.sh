#!/usr/bin/env bash
# Rebuild the built-in Twin-Burger model (models/twin_burger/) from simulated normal dives:
# the three Diagnosis Motion Sequences and rectangle missions of both sizes, both directions
# and speeds from 0.125 to 0.45 m/s, and open-loop excitation over the whole command range;
# seeds 1-3 for training and seed 101 held out for the error figures.
# Usage: scripts/build_default_model.sh [OUTPUT_DIR]   (about 4 minutes on 2 cores)
set -euo pipefail
output=${1:-models/twin_burger}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scenarios=(dms-za dms-zb dms-zc paper-normal mission-ccw mission-large-cw mission-large-ccw
           mission-fast-cw mission-fast-ccw mission-sprint-cw mission-sprint-ccw
           routine-and-mission excitation)
train=() holdout=()
for scenario in "${scenarios[@]}"; do
  for seed in 1 2 3; do
    auvdiag simulate "$scenario" --format ros2-mcap --seed "$seed" --output "$work/$scenario-s$seed" >/dev/null
    train+=("$work/$scenario-s$seed")
  done
  auvdiag simulate "$scenario" --format ros2-mcap --seed 101 --output "$work/heldout-$scenario" >/dev/null
  holdout+=(--holdout "$work/heldout-$scenario")
done
auvdiag train "${train[@]}" "${holdout[@]}" --output "$work/twin_burger" --seed 0
rm -rf "$output"
mkdir -p "$output"
cp "$work/twin_burger"/* "$output"/
