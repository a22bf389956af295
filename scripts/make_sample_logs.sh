#!/usr/bin/env bash
# Regenerate sample_logs/: small simulated dives with their ground truth (NAME.truth.json,
# NAME.truth.csv) and the report the built-in model gives (NAME.expected.json).
# Usage (from the repository root): scripts/make_sample_logs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
out=sample_logs
rm -rf "$out"/*/ "$out"/*.bag "$out"/*.json "$out"/*.csv
make() {  # scenario seed format name
  auvdiag simulate "$1" --seed "$2" --format "$3" --output "$out/$4"
  auvdiag diagnose "$out/$4" --quiet --json "$out/${4%%.*}.expected.json" || [ $? -eq 1 ]
}
make paper-flow-sensor-covered 1 ros2-mcap paper-flow-sensor-covered
make paper-normal 1 ros2-mcap paper-normal
make mission-thruster-0-dead 1 bag mission-thruster-0-dead.bag
make mission-yaw-rate-sensor-dead 1 db3 mission-yaw-rate-sensor-dead
make routine-and-mission 1 ros2-mcap routine-and-mission
