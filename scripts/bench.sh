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
bin="$(tetbench_release_bin)"
# The roofline's figures are peaks: measure the backend again before every calibrated run and
# keep, figure by figure, the faster of this and the cached calibration. One measurement can be
# far from the peak (a VM's first one read triangle setup 2.4x slower than four later ones,
# which made every fraction bound by it look 1.7x closer to its bound; docs/roofline.md).
calibrate=yes
where=()
prev=""
for arg in "$@"; do
    case "$arg" in
        --no-calibrate) calibrate=no ;;
        --cache-dir=* | --data-dir=*) where+=("$arg") ;;
    esac
    case "$prev" in --cache-dir | --data-dir) where+=("$prev" "$arg") ;; esac
    prev="$arg"
done
if [ "$calibrate" = yes ]; then
    "$bin" calibrate --force ${where[@]+"${where[@]}"} >/dev/null
fi
exec "$bin" run "$@"
