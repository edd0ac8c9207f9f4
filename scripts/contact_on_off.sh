#!/usr/bin/env bash
# General contact on and off on a shipped 3D blast (docs/verification_contact.md, "With and
# without contact"): examples/multihole_3d/bar.toml run to a late time with [contact] off, on with
# candidates = "released" and on with "cracked" (the default since 7 Dec 2026), then the nodes that
# lie inside a block of another fragment counted and drawn (runs/contact_on_off/contact_on_off.png).
#   bash scripts/contact_on_off.sh [build/bin/cdemblast] [end time, s]     (needs python3-scipy)
set -u
cd "$(dirname "$0")/.."
BIN=${1:-build/bin/cdemblast}
END=${2:-0.005}
OUT=runs/contact_on_off
mkdir -p "$OUT"
for c in off on cracked; do
  case $c in
    off) set_=(--set contact.enabled=false) ;;
    on) set_=(--set contact.enabled=true --set 'contact.candidates="released"') ;;
    cracked) set_=(--set contact.enabled=true --set 'contact.candidates="cracked"') ;;
  esac
  "$BIN" run examples/multihole_3d/bar.toml --out "$OUT/$c" --overwrite -q --threads 2 \
    --set "simulation.end_time=$END" --set "simulation.output_times=[$END]" \
    "${set_[@]}" > "$OUT/$c.log" 2>&1
  echo "contact $c: exit $?"
done
/usr/bin/python3 scripts/contact_on_off.py "without contact=$OUT/off" "contact, released faces only=$OUT/on" \
  "contact, cracked faces (default)=$OUT/cracked" --out "$OUT/contact_on_off.png"
