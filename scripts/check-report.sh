#!/usr/bin/env bash
# Browser check of an mtec HTML report: opens it in headless Chromium (Debian's `chromium`
# package), takes a screenshot, and fails if the page logs console errors, loads anything from
# the network, or has an empty plot (a figure whose SVG draws no data).
#
#   scripts/check-report.sh mtec-demo/report.html [screenshot.png]
#
# Not run by CI (it needs a browser); run it before you change the report, and look at the PNG.
set -euo pipefail
report=$(realpath "${1:?usage: check-report.sh REPORT.html [SCREENSHOT.png]}")
shot=${2:-${report%.html}.png}
if ! command -v chromium >/dev/null; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
       --disable-background-networking --disable-component-update --disable-sync
       --user-data-dir="$(mktemp -d)")
log=$(mktemp)
chromium "${flags[@]}" --enable-logging=stderr --v=0 --window-size=1280,6000 \
  --screenshot="$shot" "file://$report" 2>"$log" >/dev/null || true
dom=$(mktemp)
chromium "${flags[@]}" --dump-dom "file://$report" 2>/dev/null >"$dom"
status=0
if grep -E "CONSOLE.*(Error|error)|Uncaught" "$log"; then
  echo "FAIL: console errors"; status=1
fi
python3 - "$dom" <<'PY' || status=1
import re, sys
html = open(sys.argv[1], encoding="utf-8").read()
figs = re.findall(r'<figure class="plot">(.*?)</figure>', html, re.S)
if not figs:
    print("FAIL: no figures in the report"); sys.exit(1)
empty = []
for i, f in enumerate(figs):
    cap = re.search(r"<figcaption>(.*?)</figcaption>", f, re.S)
    drawn = len(re.findall(r"<(polyline|path|circle|polygon)\b", f)) + max(0, len(re.findall(r"<rect\b", f)) - 1)
    if drawn == 0 or "no data to plot" in f:
        empty.append(cap.group(1) if cap else f"figure {i}")
if re.search(r'(src|href)="https?://', html):
    print("FAIL: the report loads something from the network"); sys.exit(1)
if empty:
    print("FAIL: empty plots:", "; ".join(empty)); sys.exit(1)
sections = re.findall(r"<h2>(.*?)</h2>", html)
print(f"ok: {len(figs)} figures, {len(sections)} sections: " + " | ".join(sections))
PY
test -s "$shot" || { echo "FAIL: no screenshot"; status=1; }
echo "screenshot: $shot"
exit $status
