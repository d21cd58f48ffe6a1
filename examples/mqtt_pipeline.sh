#!/usr/bin/env bash
# The edge predictor on an MQTT broker, for a gateway beside the machine: CSV rows arrive on one
# topic, the compensation leaves on another. No MQTT code in thermerr-edge: it stays a stdin ->
# stdout filter between the two mosquitto clients (apt-get install mosquitto-clients).
#
#   examples/mqtt_pipeline.sh MODEL.json HOST PORT [IN_TOPIC] [OUT_TOPIC]
#
# IN_TOPIC (default thermerr/in): one CSV line per message. The FIRST message the pipeline
# receives must be the header (time_s and the model's sensor columns), then one row per
# message; so start this script before the data logger starts a run, e.g. the logger does
#     mosquitto_pub -h HOST -p PORT -q 1 -t thermerr/in -l < run.csv
# OUT_TOPIC (default thermerr/out): one line per message, `time_s,<target>_pred` first, then a
# prediction per row, published as soon as its row arrived (thermerr-edge flushes every line).
# QoS 1 on every hop: the broker does not drop a row or a prediction (at least once, in order).
#
# Environment:
#   THERMERR_EDGE   the binary (default: thermerr-edge on PATH, else target/release/thermerr-edge)
#   THERMERR_SHAPE  e.g. limit=50,rate=0.05,unit=0.1,bits=16: adds <target>_offset for the CNC
#                   (see "What the CNC can take" in the README)
set -euo pipefail

if [ $# -lt 3 ]; then
    echo "usage: $0 MODEL.json HOST PORT [IN_TOPIC] [OUT_TOPIC]" >&2
    exit 2
fi
model=$1 host=$2 port=$3 in_topic=${4:-thermerr/in} out_topic=${5:-thermerr/out}

edge=${THERMERR_EDGE:-$(command -v thermerr-edge || echo target/release/thermerr-edge)}
shape=()
if [ -n "${THERMERR_SHAPE:-}" ]; then shape=(--shape "$THERMERR_SHAPE"); fi

# rows in | predict (and shape) | predictions out; the pipeline runs until stopped (Ctrl-C), and
# pipefail makes a failure of any stage (broker gone, bad model, bad header) the script's status
mosquitto_sub -h "$host" -p "$port" -q 1 -t "$in_topic" |
    "$edge" "$model" "${shape[@]}" |
    mosquitto_pub -h "$host" -p "$port" -q 1 -t "$out_topic" -l
