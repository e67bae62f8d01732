#!/usr/bin/env bash
# Browser check of any mtec HTML report, with the checks of CI's report test
# (crates/mtec-cli/tests/report_browser.rs, which runs them on the demo's and the fl-thermal
# example's reports): opens the report in headless Chromium (Debian's `chromium` package) with
# crates/mtec-cli/tests/report_check.js injected, takes a screenshot, and fails on script errors,
# empty plots, text over a plot's data or over other labels, content wider than its box or the
# page, and captions too short to say what to look at.
#
#   scripts/check-report.sh mtec-demo/report.html [screenshot.png]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
report=$(realpath "${1:?usage: check-report.sh REPORT.html [SCREENSHOT.png]}")
shot=${2:-${report%.html}.png}
if ! command -v chromium >/dev/null; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars --no-first-run
       --disable-dev-shm-usage --user-data-dir="$(mktemp -d)")
checked=$(mktemp --suffix=.html)
python3 - "$report" "$here/crates/mtec-cli/tests/report_check.js" "$checked" <<'PY'
import sys
html, js = open(sys.argv[1], encoding="utf-8").read(), open(sys.argv[2], encoding="utf-8").read()
open(sys.argv[3], "w", encoding="utf-8").write(html.replace("<head>", "<head><script>" + js + "</script>", 1))
PY
chromium "${flags[@]}" --window-size=1200,1600 --screenshot="$shot" "file://$report" >/dev/null 2>&1
chromium "${flags[@]}" --window-size=1200,1600 --virtual-time-budget=10000 --dump-dom \
  "file://$checked" 2>/dev/null | python3 -c '
import html, json, sys
dom = sys.stdin.read()
tag = "<pre id=\"mtec-check\">"
i = dom.rfind(tag)
if i < 0:
    sys.exit("FAIL: the check script did not run")
r = json.loads(html.unescape(dom[i + len(tag):dom.index("</pre>", i)]))
bad = r["problems"] + ["script error: " + e for e in r["errors"]]
for p in bad:
    print("FAIL:", p)
print(r["figures"], "figures,", len(bad), "problem(s)")
sys.exit(1 if bad else 0)
'
echo "screenshot: $shot"
