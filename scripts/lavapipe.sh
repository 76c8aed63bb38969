# Sourced by scripts/test and scripts/demo: makes sure a Vulkan driver exists, installing Mesa's
# software one, lavapipe, when none does (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`,
# about 16 MB, with sudo when not root), and selects the Vulkan backend for wgpu so nothing falls
# back silently to a GL path that cannot render the renderer's float targets.

have_vulkan_driver() {
    compgen -G "/usr/share/vulkan/icd.d/*.json" > /dev/null || compgen -G "/etc/vulkan/icd.d/*.json" > /dev/null
}

ensure_vulkan_driver() {
    if have_vulkan_driver; then
        return 0
    fi
    echo "$0: no Vulkan driver found; installing Mesa's lavapipe (mesa-vulkan-drivers)" >&2
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    if ! command -v apt-get > /dev/null; then
        echo "$0: no apt-get here: install your distribution's Mesa Vulkan drivers (lavapipe) and rerun" >&2
        return 1
    fi
    $sudo apt-get install -y --no-install-recommends mesa-vulkan-drivers > /dev/null 2>&1 \
        || { $sudo apt-get update > /dev/null && $sudo apt-get install -y --no-install-recommends mesa-vulkan-drivers > /dev/null; }
}

ensure_vulkan_driver
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"

# The Vulkan loader prints "error: XDG_RUNTIME_DIR is invalid or not set" once per device when
# the variable is unset (CI, containers). The skinkit binary points it at a private folder itself;
# the library test processes do not, so give them the same private folder here.
if [ -z "${XDG_RUNTIME_DIR:-}" ] || [ ! -d "$XDG_RUNTIME_DIR" ]; then
    XDG_RUNTIME_DIR="${TMPDIR:-/tmp}/skinkit-runtime-$(id -u)"
    mkdir -p -m 0700 "$XDG_RUNTIME_DIR" && export XDG_RUNTIME_DIR || unset XDG_RUNTIME_DIR
fi
