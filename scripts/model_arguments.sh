# Sourced by the shipped-model scripts: their common arguments [PROFILE] [MODEL_DIR] [FORMAT]
# (profile twin_burger by default, models/PROFILE, and the format its dives are simulated
# in: ros2-mcap, or tlog for bluerov2, which is described for MAVLink logs only), and a
# scratch folder removed on exit.
profile=${1:-twin_burger}
model=${2:-models/$profile}
default_format=ros2-mcap
[[ $profile == bluerov2 ]] && default_format=tlog
format=${3:-$default_format}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
