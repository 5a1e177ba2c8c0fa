#!/usr/bin/env bash
# Runs the tetbench default suite (or `tetbench run` with the arguments given) in a release
# build: installs a Vulkan driver first if the machine has none. Results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_prerequisites
# VTK's mappers (--peers vtk, or an algorithm vtk-*) need VTK's Python package.
case " $* " in *vtk*) ensure_vtk_python ;; esac
cargo build --release -p harness --bin tetbench
exec "$(tetbench_release_bin)" run "$@"
