# Shared set-up for bench.sh and test.sh (sourced, not run). Idempotent: installs only what
# is missing, so running it again changes nothing.

# Run as root, or through sudo when not root.
as_root() {
    if [ "$(id -u)" -eq 0 ]; then
        "$@"
    elif command -v sudo >/dev/null 2>&1; then
        sudo "$@"
    else
        echo "tetbench: need root (or sudo) to run: $*" >&2
        return 1
    fi
}

APT_UPDATED=0
apt_install() {
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "tetbench: please install $* with your package manager (no apt-get here)" >&2
        return 1
    fi
    if [ "$APT_UPDATED" -eq 0 ]; then
        as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
        APT_UPDATED=1
    fi
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@"
}

# A Vulkan driver: any installed ICD (a GPU's, or Mesa's lavapipe software rasteriser) plus the
# Vulkan loader. On a machine with neither, Mesa's drivers give lavapipe.
have_vulkan_icd() {
    # Manifests named by the loader's variables first (a GPU machine whose driver lives outside
    # the standard folders, e.g. /usr/local/nvidia/share/vulkan/icd.d), colon-separated.
    local f list files
    for list in "${VK_DRIVER_FILES:-}" "${VK_ICD_FILENAMES:-}"; do
        IFS=: read -r -a files <<<"$list"
        for f in "${files[@]}"; do
            [ -n "$f" ] && [ -e "$f" ] && return 0
        done
    done
    # Any one manifest will do (`ls a b c` would fail as soon as one directory has none).
    for f in /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json \
        /usr/local/share/vulkan/icd.d/*.json; do
        [ -e "$f" ] && return 0
    done
    return 1
}
have_vulkan_loader() {
    ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || ls /usr/lib/*/libvulkan.so.1 >/dev/null 2>&1
}

ensure_prerequisites() {
    if ! command -v cargo >/dev/null 2>&1; then
        echo "tetbench: cargo not found; install Rust first (https://rustup.rs)" >&2
        exit 1
    fi
    command -v cc >/dev/null 2>&1 || apt_install gcc libc6-dev
    ensure_vulkan_runtime
}

# What a built tetbench needs to run (no compiler): the Vulkan loader and a driver.
ensure_vulkan_runtime() {
    local need=()
    have_vulkan_loader || need+=(libvulkan1)
    have_vulkan_icd || need+=(mesa-vulkan-drivers)
    if [ "${#need[@]}" -gt 0 ]; then
        echo "tetbench: installing ${need[*]}" >&2
        apt_install "${need[@]}"
    fi
    # Mesa's drivers warn (and some loaders fail) without a runtime directory.
    export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
}

# VTK for the peer algorithms (vtk-pt, vtk-raycast, vtk-zsweep) and the outside check of the
# reference: Python's `vtk` package in a virtual environment (.venv-vtk/ at the repository
# root, or $TETBENCH_VTK_VENV), never in the system Python, plus Mesa's EGL and llvmpipe so
# that VTK renders offscreen without a display or GPU. Exports TETBENCH_VTK_PYTHON.
have_lib() {
    ldconfig -p 2>/dev/null | grep -q "$1" || ls /usr/lib/*/"$1"* >/dev/null 2>&1
}
ensure_vtk_python() {
    local venv="${TETBENCH_VTK_VENV:-$PWD/.venv-vtk}"
    local need=()
    have_lib 'libEGL.so.1' || need+=(libegl1)
    have_lib 'libEGL_mesa.so.0' || need+=(libegl-mesa0)
    have_lib 'libGL.so.1' || need+=(libgl1)
    ls /usr/lib/*/dri/swrast_dri.so >/dev/null 2>&1 || need+=(libgl1-mesa-dri)
    command -v python3 >/dev/null 2>&1 || need+=(python3)
    if ! python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
        need+=(python3-venv)
    fi
    if [ "${#need[@]}" -gt 0 ]; then
        echo "tetbench: installing ${need[*]} (offscreen OpenGL and Python for VTK)" >&2
        apt_install "${need[@]}" || return 1
    fi
    local check='import vtkmodules.vtkRenderingVolume, vtkmodules.vtkRenderingOpenGL2'
    if ! "$venv/bin/python" -c "$check" >/dev/null 2>&1; then
        echo "tetbench: creating $venv with Python's vtk package (pip install vtk)" >&2
        python3 -m venv "$venv" || return 1
        "$venv/bin/python" -m pip install --quiet --disable-pip-version-check vtk || return 1
        "$venv/bin/python" -c "$check" || return 1
    fi
    export TETBENCH_VTK_PYTHON="$venv/bin/python"
}

# The release binary cargo built: under $CARGO_TARGET_DIR when set (cargo builds there), else
# target/ at the repository root.
tetbench_release_bin() {
    printf '%s/release/tetbench' "${CARGO_TARGET_DIR:-$PWD/target}"
}

# numpy for the Python example of an external renderer (examples/external/python, and
# tests/external_renderers.rs), in VTK's virtual environment: pip's vtk normally brings numpy
# along; installed here when it did not. Exports TETBENCH_VTK_PYTHON (ensure_vtk_python).
ensure_numpy_python() {
    ensure_vtk_python || return 1
    if ! "$TETBENCH_VTK_PYTHON" -c 'import numpy' >/dev/null 2>&1; then
        echo "tetbench: installing numpy into $("$TETBENCH_VTK_PYTHON" -c 'import sys; print(sys.prefix)')" >&2
        "$TETBENCH_VTK_PYTHON" -m pip install --quiet --disable-pip-version-check numpy || return 1
    fi
}

# A Chromium for the browser checks (scripts/check-site.sh, scripts/screenshot-report.sh): the
# one on the PATH, else Debian's `chromium`. Prints its path.
ensure_chromium() {
    local b
    b="$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)"
    if [ -z "$b" ]; then
        echo "tetbench: installing Debian's chromium" >&2
        apt_install chromium >&2 || return 1
        b="$(command -v chromium)"
    fi
    echo "$b"
}
