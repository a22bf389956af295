#!/usr/bin/env bash
# Regenerate sample_logs/: a normal and a faulty simulated dive in every format, each with
# its ground truth (NAME.truth.json, NAME.truth.csv) and the report the built-in model gives
# (NAME.expected.json). Usage (from anywhere): scripts/make_sample_logs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
out=sample_logs
rm -rf "${out:?}"/*
sample() {  # scenario format name
  auvdiag simulate "$1" --seed 1 --format "$2" --output "$out/$3"
  auvdiag diagnose "$out/$3" --quiet --json - > "$out/${3%%.*}.expected.json" || [ $? -eq 1 ]
}
sample paper-flow-sensor-covered ros2-mcap paper-flow-sensor-covered
sample paper-normal              ros2-mcap paper-normal
sample routine-and-mission       bag       routine-and-mission.bag
sample mission-thruster-0-dead   bag       mission-thruster-0-dead.bag
sample mission-ccw               db3       mission-ccw-db3
sample mission-yaw-rate-sensor-dead db3    mission-yaw-rate-sensor-dead-db3
sample mission-large-cw          mcap      mission-large-cw.mcap
sample mission-thruster-1-dead   mcap      mission-thruster-1-dead.mcap
sample mission-fast-ccw          tlog      mission-fast-ccw.tlog
sample paper-flow-sensor-covered tlog      paper-flow-sensor-covered-tlog.tlog
sample mission-large-ccw         bin       mission-large-ccw.bin
sample mission-yaw-rate-sensor-dead bin    mission-yaw-rate-sensor-dead-bin.bin
