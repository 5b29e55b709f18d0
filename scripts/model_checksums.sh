#!/usr/bin/env bash
# Writes (or with --check verifies) the SHA-256 checksum file <model>.sha256 beside each ONNX
# model, in sha256sum's format. The engine verifies it when it loads a model
# (docs/inference.md, "Model integrity"); tools/detector/export.py writes it for new exports.
#   scripts/model_checksums.sh              # the shipped models and the test fixtures
#   scripts/model_checksums.sh --check      # verify them (exit status 1 on a mismatch)
#   scripts/model_checksums.sh [--check] FILE.onnx...
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
if [ "${1:-}" = "--check" ]; then
  check=1
  shift
fi
if [ $# -eq 0 ]; then
  set -- models/detector/*.onnx tests/fixtures/models/*.onnx
fi
status=0
for model in "$@"; do
  dir=$(dirname "$model")
  name=$(basename "$model")
  if [ "$check" -eq 1 ]; then
    (cd "$dir" && sha256sum --check --quiet "$name.sha256") || status=1
  else
    (cd "$dir" && sha256sum "$name" > "$name.sha256")
    echo "wrote $model.sha256"
  fi
done
exit "$status"
