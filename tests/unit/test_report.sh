#!/usr/bin/env bash
# The report tool (scripts/cdem_report.py): a quick 2D run (triangles) and its report, then
# the overlay of a quad run with a copy of the first run given grading data, and a charged
# run (the SPEC 5.1 bar case, coarse) with a Kuz-Ram design. Checks that every expected
# picture exists, is a real PNG of the expected size and is not blank, that index.html and
# summary.md show every picture and reference only files that exist, the set-up tables, the
# warnings box, 2D units, report.json (warnings, charge, PPV fit, Kuz-Ram).
#
#   bash test_report.sh <cdemblast-binary> <repo-root>
set -euo pipefail

BIN=${1:?usage: test_report.sh <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: test_report.sh <cdemblast-binary> <repo-root>}
PY=/usr/bin/python3
REPORT="$ROOT/scripts/cdem_report.py"
CASE="$ROOT/examples/plate_with_hole_2d/case.toml"

fail() { echo "FAIL: $*" >&2; exit 1; }

[ -x "$PY" ] || fail "$PY not found (the report needs Debian's python3 with matplotlib)"
"$PY" -c 'import numpy, matplotlib' 2>/dev/null ||
  fail "$PY lacks numpy or matplotlib (apt-get install python3-numpy python3-matplotlib)"

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

quick=(--set mesh.generate.element_size=0.1 --set simulation.end_time=3e-4 -q)
"$BIN" run "$CASE" --out "$TMP/tri" "${quick[@]}" >"$TMP/run_tri.log" 2>&1 ||
  { cat "$TMP/run_tri.log"; fail "the triangle run failed"; }
"$BIN" run "$CASE" --out "$TMP/quad" "${quick[@]}" --set mesh.generate.quads=true \
  --set 'title="plate_quads"' >"$TMP/run_quad.log" 2>&1 ||
  { cat "$TMP/run_quad.log"; fail "the quad run failed"; }

# A run with grading data: the triangle run plus a grading curve and d40/d80 in its summary.
mkdir "$TMP/graded"
cp -r "$TMP/tri/." "$TMP/graded/"
"$PY" - "$TMP/graded/summary.json" <<'EOF'
import json, sys
p = sys.argv[1]
s = json.load(open(p))
s["title"] = "plate_graded"
s["fragments"] = 5
s["d40_m"], s["d80_m"] = 0.03, 0.07
s["grading"] = {"size_m": [0.01, 0.02, 0.04, 0.06, 0.1], "passing_pct": [5, 20, 50, 75, 100]}
s["funnel_depth_m"] = 0.25
json.dump(s, open(p, "w"))
EOF

# A charged run (SPEC 5.1 bar case, coarse and short): charges, powder factor, PPV, warnings,
# and the Kuz-Ram curves of a design file.
"$BIN" run "$ROOT/examples/single_hole_2d/bar.toml" --out "$TMP/bar" -q \
  --set mesh.generate.element_size=0.2 --set simulation.end_time=1e-3 \
  --set 'simulation.output_times=[2.5e-4,1e-3]' >"$TMP/run_bar.log" 2>&1 ||
  { cat "$TMP/run_bar.log"; fail "the charged run failed"; }
cat >"$TMP/design.toml" <<'EOT'
[design]
rock_factor = 7.0
burden = 1.0
spacing = 1.2
bench_height = 1.0
charge_per_hole = 5.0
EOT

"$PY" "$REPORT" "$TMP/tri" >"$TMP/rep1.log" 2>&1 || { cat "$TMP/rep1.log"; fail "report of one run failed"; }
"$PY" "$REPORT" "$TMP/bar" --design "$TMP/design.toml" >"$TMP/rep4.log" 2>&1 ||
  { cat "$TMP/rep4.log"; fail "report of the charged run failed"; }
"$PY" "$REPORT" "$TMP/graded" "$TMP/quad" --out "$TMP/cmp" >"$TMP/rep2.log" 2>&1 ||
  { cat "$TMP/rep2.log"; fail "overlay report of two runs failed"; }

# A directory that does not exist is an error (exit status 2), not a traceback.
set +e
"$PY" "$REPORT" "$TMP/no_such_run" >"$TMP/rep3.log" 2>&1
rc=$?
set -e
[ "$rc" = 2 ] || { cat "$TMP/rep3.log"; fail "a missing run directory gave exit status $rc, expected 2"; }
grep -q "not a directory" "$TMP/rep3.log" || fail "no clear message for a missing run directory"

"$PY" - "$TMP" <<'EOF'
import os, re, struct, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg

tmp = sys.argv[1]
errors = []

def check_png(path, size=None, min_ink=0.01):
    """A real, non-blank PNG; size = (width, height) when it is fixed by the script; min_ink:
    the least fraction of non-white pixels (line plots ~0.02, field maps far more)."""
    if not os.path.isfile(path):
        errors.append(f"{path}: missing")
        return
    with open(path, "rb") as f:
        head = f.read(33)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        errors.append(f"{path}: not a PNG file")
        return
    w, h = struct.unpack(">II", head[16:24])
    img = mpimg.imread(path)
    if img.shape[1] != w or img.shape[0] != h:
        errors.append(f"{path}: IHDR says {w}x{h}, the image is {img.shape[1]}x{img.shape[0]}")
    if size is not None and (w, h) != size:
        errors.append(f"{path}: {w}x{h} pixels, expected {size[0]}x{size[1]}")
    if not (400 <= w <= 4000 and 300 <= h <= 4000):
        errors.append(f"{path}: implausible size {w}x{h}")
    rgb = img[..., :3].astype(float)
    if rgb.std() < 0.02:
        errors.append(f"{path}: blank (pixel std {rgb.std():.4f})")
    inked = np.mean(rgb.min(axis=2) < 0.9)
    if inked < min_ink:
        errors.append(f"{path}: almost nothing drawn ({100 * inked:.1f} % of the pixels)")

def check_links(out_dir):
    """index.html and summary.md reference only files that exist (and reference the PNGs)."""
    for name in ("index.html", "summary.md"):
        p = os.path.join(out_dir, name)
        if not os.path.isfile(p):
            errors.append(f"{p}: missing")
            return
    text = open(os.path.join(out_dir, "index.html")).read()
    if not text.lstrip().lower().startswith("<!doctype html>") or "</html>" not in text:
        errors.append(f"{out_dir}/index.html: not a complete HTML page")
    refs = re.findall(r'(?:src|href)="([^"]+)"', text)
    md = open(os.path.join(out_dir, "summary.md")).read()
    refs_md = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md)
    for r in refs + refs_md:
        if re.match(r"^[a-z]+:", r) or r.startswith("#"):
            continue
        if not os.path.exists(os.path.join(out_dir, r)):
            errors.append(f"{out_dir}: reference to missing file {r}")
    for png in sorted(f for f in os.listdir(out_dir) if f.endswith(".png")):
        if png not in refs:
            errors.append(f"{out_dir}/index.html does not show {png}")
        if png not in refs_md:
            errors.append(f"{out_dir}/summary.md does not show {png}")
    return text, md

fixed = {"monitors.png": (1350, 1425), "fracture.png": (1275, 750), "energy.png": (1650, 1200)}

def has_grading(run):
    """Did the run write grading data (a grading.csv with a data row)?"""
    p = os.path.join(run, "grading.csv")
    return os.path.isfile(p) and len(open(p).read().split()) > 1

def has_fragment_ids(run):
    fields = sorted(os.listdir(os.path.join(run, "fields")))
    return b'Name="fragment_id"' in open(os.path.join(run, "fields", fields[-1]), "rb").read(4096)

# One run. Grading and fragment pictures are expected when the run wrote their data.
tri = os.path.join(tmp, "tri")
one = os.path.join(tri, "report")
pngs = ["setup.png", "monitors.png", "fracture.png", "energy.png", "damage_maps.png",
        "von_mises_maps.png", "damage_final.png"]
pngs += ["fragments_final.png"] if has_fragment_ids(tri) else []
for png in pngs:
    check_png(os.path.join(one, png), fixed.get(png), 0.01 if png in fixed else 0.3)
if has_grading(tri):
    check_png(os.path.join(one, "grading.png"), (1275, 825))
elif os.path.exists(os.path.join(one, "grading.png")):
    errors.append(f"{one}/grading.png: written without grading data")
res = check_links(one)
if res:
    html, md = res
    if not has_grading(tri) and "grading.png skipped" not in md:
        errors.append(f"{one}/summary.md: no note that grading.png was skipped")
    for needle in ("fracture degree (area)", "plate_with_hole_2d", "peak von Mises", "Set-up",
                   "Materials", "Interface laws", "n/a (2D)", "J/m", "m³/m"):
        if needle not in md or needle not in html:
            errors.append(f"{one}: '{needle}' missing from summary.md or index.html")
    if 'id="warnings"' not in html or html.index('id="warnings"') > html.index("Key numbers"):
        errors.append(f"{one}/index.html: no warnings box above the key numbers")

# report.json: every number, and the warnings list (merged with summary.json's).
import json
rj = json.load(open(os.path.join(one, "report.json")))
if not isinstance(rj.get("warnings"), list) or rj["runs"][0]["setup"]["dimension"] != 2:
    errors.append(f"{one}/report.json: no warnings list or set-up")

# The charged run: charge and powder factor, warnings that fire, PPV fit, Kuz-Ram.
bar = os.path.join(tmp, "bar", "report")
for png in ("setup.png", "ppv.png"):
    check_png(os.path.join(bar, png), None, 0.01)
res = check_links(bar)
rj = json.load(open(os.path.join(bar, "report.json")))
codes = {w["code"] for w in rj["warnings"]}
for code in ("powder_factor", "charge_larger_than_block"):
    if code not in codes:
        errors.append(f"{bar}/report.json: warning '{code}' did not fire ({sorted(codes)})")
# ... and the same warnings in the run's summary.json (issue 18: listed there as `warnings`).
sj = json.load(open(os.path.join(tmp, "bar", "summary.json")))
if {w.get("code") for w in sj.get("warnings") or []} != codes:
    errors.append(f"{tmp}/bar/summary.json: warnings {sj.get('warnings')} are not the report's {sorted(codes)}")
st = rj["runs"][0]["setup"]
if abs(st["charge_mass_kg"] - 1150 * 0.1 * 0.5) > 1e-6 or not st["per_metre"]:
    errors.append(f"{bar}/report.json: charge {st['charge_mass_kg']} kg/m, expected 57.5 kg/m")
if not (rj["runs"][0]["ppv"]["fit"] or {}).get("beta"):
    errors.append(f"{bar}/report.json: no PPV fit")
if not (rj.get("kuz_ram") or {}).get("x50_m"):
    errors.append(f"{bar}/report.json: no Kuz-Ram prediction of the design")
if res:
    for needle in ("57.5", "kg/m", "powder factor", "Warnings", "Peak particle velocity",
                   "Kuz-Ram"):
        if needle not in res[0]:
            errors.append(f"{bar}/index.html: '{needle}' missing")

# Overlay of two runs, one with grading data (--out).
cmp_dir = os.path.join(tmp, "cmp")
for png, size in (("monitors.png", (1350, 1425)), ("fracture.png", (2100, 720)),
                  ("energy.png", (2250, 1275)), ("grading.png", (1275, 825)),
                  ("damage_final_compare.png", None)):
    check_png(os.path.join(cmp_dir, png), size, 0.3 if size is None else 0.01)
res = check_links(cmp_dir)
if res:
    needles = ["plate_graded", "plate_quads", "d40 (40 % passing)", "funnel depth"]
    if not has_grading(os.path.join(tmp, "quad")):
        needles.append("left out of grading.png")
    for needle in needles:
        if needle not in res[0] or needle not in res[1]:
            errors.append(f"{cmp_dir}: '{needle}' missing from summary.md or index.html")

if errors:
    print("\n".join(errors))
    sys.exit(1)
print("report checks passed")
EOF
echo "PASS: test_report (${SECONDS} s)"
