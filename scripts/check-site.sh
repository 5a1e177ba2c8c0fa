#!/usr/bin/env bash
# Walks a site written by `tetbench publish` in headless Chromium (scripts/check_site.py): every
# page loads with no console error, every link and image resolves, no name's markup runs.
#   scripts/check-site.sh SITE_DIR [check_site.py options]
# Installs Debian's chromium when no Chromium is on the PATH (as scripts/screenshot-report.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
site="${1:?usage: scripts/check-site.sh SITE_DIR [--expect-text TEXT] [--json OUT]}"
shift
browser="$(ensure_chromium)" || { echo "check-site: no Chromium, and it could not be installed" >&2; exit 1; }
command -v python3 >/dev/null 2>&1 || apt_install python3 >&2
exec python3 scripts/check_site.py "$site" --browser "$browser" "$@"
