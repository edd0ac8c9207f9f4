#!/usr/bin/env bash
# The study command (docs/study.md): two tiny variants of the SPEC 5.1 bar case (coarse mesh,
# 1 ms) that differ only in their charge (half and full length), run with
# `cdemblast study`, then compared: study.json, index.html and real, non-blank PNGs; the
# recommendation names the variant with the larger throw as the one with most fly-rock and the
# other as the one that limits it; a second call resumes (reruns nothing); --no-run compares
# only; a bad study file is an input error (exit 2).
#
#   bash test_study.sh <cdemblast-binary> <repo-root>
set -euo pipefail

BIN=${1:?usage: test_study.sh <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: test_study.sh <cdemblast-binary> <repo-root>}
PY=/usr/bin/python3

fail() { echo "FAIL: $*" >&2; exit 1; }
[ -x "$PY" ] || fail "$PY not found (the study needs Debian's python3 with matplotlib)"

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
export OMP_WAIT_POLICY=PASSIVE

cat >"$TMP/tiny.toml" <<EOT
[study]
title = "tiny: half against full charge"
base = "$ROOT/examples/single_hole_2d/bar.toml"
set = ["mesh.generate.element_size=0.2", "simulation.end_time=1e-3",
       "simulation.history_interval=1e-5"]

[[variant]]
name = "half"
label = "half charge"
set = ["hole.0.charge.0.length=0.25"]

[[variant]]
name = "full"
label = "full charge"

[compare]
times = [5e-4, 1e-3]

[design]
rock_factor = 7.0
burden = 1.0
spacing = 1.2
bench_height = 1.0
charge_per_hole = 5.0
[design.funnel]
shape = "box"
lo = [1.0, 1.0]
hi = [3.0, 2.0]
EOT

"$BIN" study "$TMP/tiny.toml" --out "$TMP/st" --threads 1 >"$TMP/study1.log" 2>&1 ||
  { cat "$TMP/study1.log"; fail "cdemblast study failed"; }
grep -q "dropped\|drops output times" "$TMP/study1.log" ||
  { cat "$TMP/study1.log"; fail "no notice that output times past the end were dropped"; }
stamp=$(stat -c %Y "$TMP/st/full/summary.json")

"$PY" - "$TMP/st" <<'EOT'
import json, os, struct, sys
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mpimg

d = sys.argv[1]
errors = []
s = json.load(open(os.path.join(d, "study.json")))
names = [v["name"] for v in s["variants"]]
if names != ["half", "full"]:
    errors.append(f"variants {names}")
v = {x["name"]: x for x in s["variants"]}
rec = {g["goal"]: g for g in s["recommendation"]["goals"]}
if rec["limits fly-rock"]["winner"] != "half":
    errors.append(f"limits fly-rock: {rec['limits fly-rock']['winner']}, expected half")
if s["recommendation"]["most_fly_rock"] != "full":
    errors.append(f"most fly-rock: {s['recommendation']['most_fly_rock']}, expected full")
for g in rec.values():
    if not g["criteria"] or not g["rule"] or not g["decided_by"]:
        errors.append(f"{g['goal']}: criteria not stated")
fh, ff = v["half"]["fly_rock"], v["full"]["fly_rock"]
# (the throw as the recommendation measures it: the speed exceeded by the top share of the
# fragments' volume, and the largest rise. The single fastest fragment is no measure of the
# throw: on this 256-block mesh it is one small block of the collar, 346-355 m/s in both
# variants, and which of the two has it changes with the last bits of a sum)
if not (ff["quantile_launch_speed_m_s"] > fh["quantile_launch_speed_m_s"]
        and ff["max_vertical_displacement_m"] > fh["max_vertical_displacement_m"]):
    errors.append(f"the full charge does not throw more: {fh} {ff}")
if abs(v["full"]["setup"]["charge_mass_kg"] - 2 * v["half"]["setup"]["charge_mass_kg"]) > 1e-9:
    errors.append("charges not 1:2")
for x in s["variants"]:
    for key in ("fracture_degree", "grading", "funnel", "fly_rock", "energy", "monitors",
                "design_funnel", "ppv"):
        if x.get(key) is None:
            errors.append(f"{x['name']}: no {key}")
    if x["funnel"]["l_y_m"] is not None or "l_y_m" not in x["funnel"]["not_in_2d"]:
        errors.append(f"{x['name']}: l_y should be n/a in 2D")
    if x["design_funnel"].get("fracture_degree") is None:
        errors.append(f"{x['name']}: no fracture degree inside the design funnel")
if not (s.get("kuz_ram") or {}).get("x50_m"):
    errors.append("no Kuz-Ram prediction")
for x in s["variants"]:  # fracture.csv has degree_area_<region> (the main region "rock")
    if "rock" not in (x["fracture_degree"].get("by_region") or {}):
        errors.append(f"{x['name']}: no per-region fracture degree for 'rock'")
html = open(os.path.join(d, "index.html")).read()
for needle in ("Recommendation", "limits fly-rock", "breaks the rock best", "rule:",
               "half charge", "full charge", "n/a (2D)"):
    if needle not in html:
        errors.append(f"index.html lacks '{needle}'")
want = ["vertical_displacement.png", "monitors.png", "monitors_vertical.png", "fracture.png",
        "fracture_regions.png", "grading.png", "launch_speeds.png", "energy.png", "energy_budget.png", "ppv.png"]
for p in want:
    path = os.path.join(d, p)
    if not os.path.isfile(path):
        errors.append(f"{p} missing")
        continue
    if f'src="{p}"' not in html:
        errors.append(f"index.html does not show {p}")
    head = open(path, "rb").read(24)
    w, h = struct.unpack(">II", head[16:24])
    img = mpimg.imread(path)[..., :3]
    if head[:8] != b"\x89PNG\r\n\x1a\n" or (img.shape[1], img.shape[0]) != (w, h):
        errors.append(f"{p}: not a PNG of its declared size")
    if img.std() < 0.02 or np.mean(img.min(axis=2) < 0.9) < 0.01:
        errors.append(f"{p}: blank")
if errors:
    print("\n".join(errors))
    sys.exit(1)
print("study checks passed")
EOT

# Resume: the same study again reruns nothing.
"$PY" "$ROOT/scripts/cdem_study.py" "$TMP/tiny.toml" --out "$TMP/st" --threads 1 --bin "$BIN" \
  --no-pictures >"$TMP/study2.log" 2>&1 ||
  { cat "$TMP/study2.log"; fail "the second cdemblast study failed"; }
[ "$(grep -c 'not rerun' "$TMP/study2.log")" = 2 ] ||
  { cat "$TMP/study2.log"; fail "the second call did not resume both variants"; }
[ "$(stat -c %Y "$TMP/st/full/summary.json")" = "$stamp" ] || fail "a finished run was rerun"
# A changed variant is rerun: its resolved case no longer matches.
sed -i 's/hole.0.charge.0.length=0.25/hole.0.charge.0.length=0.3/' "$TMP/tiny.toml"
"$PY" "$ROOT/scripts/cdem_study.py" "$TMP/tiny.toml" --out "$TMP/st" --no-run --no-pictures \
  >"$TMP/study3.log" 2>&1 ||
  { cat "$TMP/study3.log"; fail "--no-run failed"; }
grep -q "running" "$TMP/study3.log" && fail "--no-run ran a case"
"$PY" "$ROOT/scripts/cdem_study.py" "$TMP/tiny.toml" --out "$TMP/st" --threads 1 \
  --bin "$BIN" --no-pictures >"$TMP/study4.log" 2>&1 ||
  { cat "$TMP/study4.log"; fail "the study with a changed variant failed"; }
grep -q "running half" "$TMP/study4.log" || { cat "$TMP/study4.log"; fail "the changed variant was not rerun"; }
grep -q "full: finished run found" "$TMP/study4.log" || fail "the unchanged variant was rerun"

# Input errors: exit status 2 and a message naming the file.
printf '[study]\nbase = "nope.toml"\n' >"$TMP/bad.toml"
set +e
"$BIN" study "$TMP/bad.toml" --out "$TMP/bad" >"$TMP/bad.log" 2>&1
rc=$?
set -e
[ "$rc" = 2 ] || { cat "$TMP/bad.log"; fail "a bad study file gave exit status $rc, expected 2"; }
grep -q "bad.toml" "$TMP/bad.log" || fail "the error does not name the study file"
echo "PASS: test_study (${SECONDS} s)"
