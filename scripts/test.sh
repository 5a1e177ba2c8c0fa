#!/usr/bin/env bash
# Runs the whole test suite (`cargo test --workspace`), installing a Vulkan driver first if the
# machine has none (GPU tests then run on Mesa's lavapipe), and VTK's Python package into
# .venv-vtk/ for the outside check of the reference. Extra arguments go to cargo test.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_prerequisites
# The outside check of the reference (tests/vtk_vs_reference.rs) needs VTK; when it cannot be
# installed the test fails with the reason instead of being skipped.
ensure_vtk_python || echo "tetbench: could not install VTK (see above); tests/vtk_vs_reference.rs will fail" >&2
# The Python example of an external renderer (tests/external_renderers.rs) needs numpy.
ensure_numpy_python || echo "tetbench: could not install numpy (see above); tests/external_renderers.rs will fail" >&2
# The published site's browser walk (harness/tests/publish_site.rs) needs Chromium; installed
# here so that no test waits on apt.
ensure_chromium >/dev/null || echo "tetbench: could not install chromium (see above); harness/tests/publish_site.rs will fail" >&2
exec cargo test --workspace "$@"
