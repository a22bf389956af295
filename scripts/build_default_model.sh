#!/usr/bin/env bash
# Rebuild a shipped model (models/VEHICLE/) from simulated normal dives of a built-in profile:
# each Diagnosis Motion Sequence alone and all of them before a mission, rectangle missions
# of both sizes, both directions and speeds from 0.125 to 0.45 m/s, and open-loop excitation
# over the whole command range; seeds 1-3 for training and seed 101 held out for the error
# figures.
# Usage: scripts/build_default_model.sh [PROFILE] [OUTPUT_DIR] [FORMAT]
#   PROFILE: twin_burger (default), three_thruster or bluerov2; OUTPUT_DIR: models/PROFILE;
#   FORMAT: the log format the dives are written in (default ros2-mcap; tlog for bluerov2,
#   which is described for MAVLink logs only).
#   About 4-5 minutes on 2 cores for the Twin-Burger, longer for vehicles with more DMSs.
set -euo pipefail
profile=${1:-twin_burger}
output=${2:-models/$profile}
default_format=ros2-mcap
[[ $profile == bluerov2 ]] && default_format=tlog
format=${3:-$default_format}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mapfile -t dms < <(auvdiag scenarios --profile "$profile" | awk '$1 ~ /^dms-[^-]+$/ {print $1}')
# Full-range excitation of six motors spins the BlueROV2 far beyond anything its missions
# do; its model learns from its DMSs (one per motor) and missions only.
excitation=(excitation)
[[ $profile == bluerov2 ]] && excitation=()
scenarios=("${dms[@]}" paper-normal mission-ccw mission-large-cw mission-large-ccw
           mission-fast-cw mission-fast-ccw mission-sprint-cw mission-sprint-ccw
           all-dms-and-mission "${excitation[@]}")
train=() holdout=()
for scenario in "${scenarios[@]}"; do
  for seed in 1 2 3; do
    auvdiag simulate "$scenario" --profile "$profile" --format "$format" --seed "$seed" \
      --output "$work/$scenario-s$seed" >/dev/null
    train+=("$work/$scenario-s$seed")
  done
  auvdiag simulate "$scenario" --profile "$profile" --format "$format" --seed 101 \
    --output "$work/heldout-$scenario" >/dev/null
  holdout+=(--holdout "$work/heldout-$scenario")
done
auvdiag train "${train[@]}" "${holdout[@]}" --profile "$profile" --output "$work/model" --seed 0
rm -rf "$output"
mkdir -p "$output"
cp "$work/model"/* "$output"/
