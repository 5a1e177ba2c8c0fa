#!/usr/bin/env bash
# Screenshots a run's index.html in headless Chromium, to check the report renders (fonts,
# charts, images) on a machine without a display: scripts/screenshot-report.sh OUT_DIR [PNG]
# Writes OUT_DIR/report-screenshot.png unless PNG is given. Installs Debian's chromium if absent.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
out="${1:?usage: scripts/screenshot-report.sh OUT_DIR [PNG]}"
html="$(cd "$out" && pwd)/index.html"
png="${2:-$out/report-screenshot.png}"
[ -f "$html" ] || { echo "no $html (run tetbench run --out $out first)" >&2; exit 1; }
browser="$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)"
if [ -z "$browser" ]; then
    apt_install chromium
    browser="$(command -v chromium)"
fi
profile="$(mktemp -d)"
trap 'rm -rf "$profile"' EXIT
sandbox=()
[ "$(id -u)" -eq 0 ] && sandbox=(--no-sandbox)
png_abs="$(cd "$(dirname "$png")" && pwd)/$(basename "$png")"
"$browser" --headless "${sandbox[@]}" --disable-gpu --disable-background-networking \
    --disable-component-update --disable-sync --no-first-run --hide-scrollbars \
    --user-data-dir="$profile" --window-size="${WINDOW_SIZE:-1400,3000}" \
    --screenshot="$png_abs" "file://$html" 2>/dev/null
echo "wrote $png_abs"
