#!/usr/bin/env bash
# Runs the whole test suite (`cargo test --workspace`), installing a Vulkan driver first if the
# machine has none (GPU tests then run on Mesa's lavapipe). Extra arguments go to cargo test.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_prerequisites
exec cargo test --workspace "$@"
