# Sourced by scripts/test: the demo's report page is opened in headless Chromium (Debian's
# `chromium` package) by a node script using playwright-core (tools/page-check; no browser is
# downloaded). This installs what is missing: chromium, nodejs and npm with apt-get (sudo when not
# root), then the checker's one npm package. When that cannot be done it says why and goes on: the
# page test then skips with the reason, and every other test still runs.

ensure_page_checker() {
    local sudo="" missing=()
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    [ -x /usr/bin/chromium ] || [ -n "${CHROMIUM:-}" ] || missing+=(chromium)
    command -v node > /dev/null || missing+=(nodejs)
    command -v npm > /dev/null || missing+=(npm)
    if [ "${#missing[@]}" -gt 0 ]; then
        if ! command -v apt-get > /dev/null; then
            echo "$0: the report page test needs ${missing[*]}: install them and rerun (it is skipped meanwhile)" >&2
            return 0
        fi
        echo "$0: installing ${missing[*]} for the report page test" >&2
        $sudo apt-get install -y --no-install-recommends "${missing[@]}" > /dev/null 2>&1 \
            || { $sudo apt-get update > /dev/null && $sudo apt-get install -y --no-install-recommends "${missing[@]}" > /dev/null; } \
            || { echo "$0: could not install ${missing[*]}: the report page test will be skipped" >&2; return 0; }
    fi
    if [ ! -d tools/page-check/node_modules/playwright-core ]; then
        (cd tools/page-check && npm ci --no-audit --no-fund --silent) \
            || echo "$0: npm ci failed in tools/page-check: the report page test will be skipped" >&2
    fi
}

ensure_page_checker
