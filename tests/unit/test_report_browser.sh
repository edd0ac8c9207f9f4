#!/usr/bin/env bash
# The report page in a browser: a quick 2D run (the SPEC 5.1 bar case, coarse) and its report,
# index.html rendered by headless Chromium. Every <img>
# must load and decode (naturalWidth > 0) and every link must point to an existing file; a copy
# of the page with a broken image must be caught (the check can fail). A screenshot of the
# rendered page must not be blank. Skipped (exit 77) when chromium is not installed.
#
#   bash test_report_browser.sh <cdemblast-binary> <repo-root>
set -euo pipefail
BIN=${1:?usage: test_report_browser.sh <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: test_report_browser.sh <cdemblast-binary> <repo-root>}
PY=/usr/bin/python3
CHROMIUM=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$CHROMIUM" ]; then
  echo "SKIP: the test-only Debian package chromium is not installed (apt-get install chromium)"
  exit 77
fi
fail() { echo "FAIL: $*" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
export OMP_WAIT_POLICY=PASSIVE

"$BIN" run "$ROOT/examples/single_hole_2d/bar.toml" --out "$TMP/run" -q --threads 1 \
  --set mesh.generate.element_size=0.2 --set simulation.end_time=1e-3 \
  --set 'simulation.output_times=[2.5e-4,1e-3]' >"$TMP/run.log" 2>&1 || { cat "$TMP/run.log"; fail "run"; }
"$BIN" report "$TMP/run" >"$TMP/report.log" 2>&1 || { cat "$TMP/report.log"; fail "report"; }

browser() {  # browser OUT ARGS...: headless Chromium with a fresh profile, no network
  local out=$1
  shift
  timeout 120 "$CHROMIUM" --headless --no-sandbox --disable-gpu --disable-background-networking \
    --disable-component-update --no-first-run --disable-sync --user-data-dir="$TMP/profile" \
    --virtual-time-budget=10000 "$@" >"$out" 2>"$TMP/chromium.err"
}

# The page as it is, with a script appended that lists what the browser loaded.
"$PY" - "$TMP/run/report" <<'EOT'
import os, sys
d = sys.argv[1]
js = """<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var res = {images: imgs.map(function (i) {
               return [i.getAttribute("src"), i.complete, i.naturalWidth, i.naturalHeight]; }),
             links: Array.prototype.slice.call(document.querySelectorAll("a[href]"))
               .map(function (a) { return a.getAttribute("href"); }),
             title: document.title};
  var pre = document.createElement("pre");
  pre.id = "browser-check";
  pre.textContent = JSON.stringify(res);
  document.body.appendChild(pre);
});
</script>"""
page = open(os.path.join(d, "index.html")).read()
open(os.path.join(d, "_check.html"), "w").write(page.replace("</body>", js + "</body>"))
broken = page.replace('src="energy.png"', 'src="no_such_picture.png"')
open(os.path.join(d, "_check_broken.html"), "w").write(broken.replace("</body>", js + "</body>"))
EOT
browser "$TMP/dom.html" --dump-dom "file://$TMP/run/report/_check.html" ||
  { cat "$TMP/chromium.err"; fail "chromium could not render index.html"; }
browser "$TMP/dom_broken.html" --dump-dom "file://$TMP/run/report/_check_broken.html" ||
  fail "chromium could not render the broken copy"
browser "$TMP/shot.log" --window-size=1280,2000 --screenshot="$TMP/shot.png" \
  "file://$TMP/run/report/index.html" || fail "chromium could not take a screenshot"

"$PY" - "$TMP" <<'EOT'
import html, json, os, re, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg

tmp = sys.argv[1]
report = os.path.join(tmp, "run", "report")
errors = []

def loaded(dom_file):
    m = re.search(r'<pre id="browser-check">(.*?)</pre>', open(dom_file).read(), re.S)
    if not m:
        errors.append(f"{dom_file}: the page's load handler did not run")
        return None
    return json.loads(html.unescape(m.group(1)))

res = loaded(os.path.join(tmp, "dom.html"))
if res:
    pngs = sorted(f for f in os.listdir(report) if f.endswith(".png"))
    srcs = [i[0] for i in res["images"]]
    if sorted(srcs) != pngs:
        errors.append(f"images on the page {sorted(srcs)} != PNGs written {pngs}")
    for src, complete, w, h in res["images"]:
        if not (complete and w > 0 and h > 0):
            errors.append(f"image {src} did not load ({complete}, {w}x{h})")
    for href in res["links"]:
        if not re.match(r"^[a-z]+:|^#", href) and not os.path.exists(os.path.join(report, href)):
            errors.append(f"link to a missing file: {href}")
    if not res["title"].startswith("Run report"):
        errors.append(f"page title {res['title']!r}")
bad = loaded(os.path.join(tmp, "dom_broken.html"))
if bad:
    broken = [i[0] for i in bad["images"] if not (i[1] and i[2] > 0)]
    if broken != ["no_such_picture.png"]:
        errors.append(f"the broken copy was not caught: {broken}")
shot = os.path.join(tmp, "shot.png")
if not os.path.isfile(shot):
    errors.append("no screenshot")
else:
    img = mpimg.imread(shot)[..., :3]
    if img.shape[1] != 1280 or img.std() < 0.02:
        errors.append(f"screenshot {img.shape} blank or of the wrong size")
if errors:
    print("\n".join(errors))
    sys.exit(1)
print(f"chromium loaded {len(res['images'])} images and {len(res['links'])} links")
EOT
echo "PASS: test_report_browser (${SECONDS} s)"
