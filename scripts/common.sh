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
    # Any one manifest will do (`ls a b c` would fail as soon as one directory has none).
    local f
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
    local need=()
    command -v cc >/dev/null 2>&1 || need+=(gcc libc6-dev)
    have_vulkan_loader || need+=(libvulkan1)
    have_vulkan_icd || need+=(mesa-vulkan-drivers)
    if [ "${#need[@]}" -gt 0 ]; then
        echo "tetbench: installing ${need[*]}" >&2
        apt_install "${need[@]}"
    fi
    # Mesa's drivers warn (and some loaders fail) without a runtime directory.
    export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
}
