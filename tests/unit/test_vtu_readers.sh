#!/usr/bin/env bash
# The VTU outputs read by VTK's own XML reader (python3-vtk9) and by meshio (python3-meshio):
# a 2D run (an empty crack file at t = 0, cracks later) and a short 3D run (tetrahedra). Every
# fields/*.vtu and cracks/*.vtu must read without an error or warning in both, give the
# project's reader's point and cell counts, carry TimeValue = the PVD time, name the stress
# components xx, yy, zz, xy, yz, xz, and declare every array with the same type in every file
# of a series. VTK also runs its geometry filter (what ParaView draws) on each file.
# Skipped (exit 77) when python3-vtk9 or python3-meshio is not installed.
#
#   bash test_vtu_readers.sh <cdemblast-binary> <repo-root>
set -euo pipefail
BIN=${1:?usage: test_vtu_readers.sh <cdemblast-binary> <repo-root>}
ROOT=${2:?usage: test_vtu_readers.sh <cdemblast-binary> <repo-root>}
PY=/usr/bin/python3
missing=()
"$PY" -c 'import vtk' 2>/dev/null || missing+=("python3-vtk9 (import vtk)")
"$PY" -c 'import meshio' 2>/dev/null || missing+=("python3-meshio (import meshio)")
if [ ${#missing[@]} -gt 0 ]; then
  echo "SKIP: test-only Debian packages missing: ${missing[*]}; apt-get install python3-vtk9 python3-meshio"
  exit 77
fi
fail() { echo "FAIL: $*" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
export OMP_WAIT_POLICY=PASSIVE

"$BIN" run "$ROOT/examples/single_hole_2d/bar.toml" --out "$TMP/r2d" -q --threads 1 \
  --set mesh.generate.element_size=0.2 --set simulation.end_time=5e-4 \
  --set 'simulation.output_times=[2.5e-4]' >"$TMP/r2d.log" 2>&1 || { cat "$TMP/r2d.log"; fail "2D run"; }
"$BIN" run "$ROOT/examples/multihole_3d/bar.toml" --out "$TMP/r3d" -q --threads 1 \
  --set mesh.generate.element_size=0.25 --set simulation.end_time=3e-5 \
  --set 'simulation.output_times=[1.5e-5]' >"$TMP/r3d.log" 2>&1 || { cat "$TMP/r3d.log"; fail "3D run"; }

PYTHONPATH="$ROOT/python" "$PY" - "$TMP/r2d" "$TMP/r3d" <<'EOT'
import io, logging, os, sys, warnings, contextlib
import vtk
import meshio
from cdemblast.vtu import read_pvd, read_vtu

errors = []
log = io.StringIO()
handler = logging.StreamHandler(log)
logging.getLogger().addHandler(handler)
ow = vtk.vtkStringOutputWindow()
vtk.vtkOutputWindow.SetInstance(ow)
KIND = {"fields": 0, "cracks": 0}
for run in sys.argv[1:]:
    for series in ("fields", "cracks"):
        types = {}
        steps = read_pvd(os.path.join(run, series + ".pvd"))
        if len(steps) < 2:
            errors.append(f"{run}/{series}.pvd: {len(steps)} steps")
        for t, path in steps:
            name = os.path.relpath(path, run)
            ours = read_vtu(path)
            # VTK's XML reader
            r = vtk.vtkXMLUnstructuredGridReader()
            r.SetFileName(path)
            r.Update()
            g = r.GetOutput()
            geo = vtk.vtkGeometryFilter()
            geo.SetInputData(g)
            geo.Update()
            text = ow.GetOutput()
            if text.strip():
                errors.append(f"{name}: VTK says: {text.strip()[:300]}")
                ow = vtk.vtkStringOutputWindow()
                vtk.vtkOutputWindow.SetInstance(ow)
            ncells = g.GetNumberOfCells() - (1 if ours.placeholder else 0)
            if g.GetNumberOfPoints() != ours.npoints or ncells != ours.ncells:
                errors.append(f"{name}: VTK {g.GetNumberOfPoints()} points {g.GetNumberOfCells()} "
                              f"cells, ours {ours.npoints} / {ours.ncells}")
            tv = g.GetFieldData().GetArray("TimeValue")
            if tv is None or abs(tv.GetValue(0) - t) > 1e-15 * max(1.0, abs(t)):
                errors.append(f"{name}: TimeValue {tv.GetValue(0) if tv else None}, PVD {t}")
            cd = g.GetCellData()
            for i in range(cd.GetNumberOfArrays()):
                a = cd.GetArray(i)
                key = ("cell", a.GetName())
                types.setdefault(key, set()).add((a.GetDataTypeAsString(), a.GetNumberOfComponents()))
                if a.GetNumberOfComponents() == 6:
                    names = [a.GetComponentName(k) for k in range(6)]
                    if names != ["xx", "yy", "zz", "xy", "yz", "xz"]:
                        errors.append(f"{name}: {a.GetName()} components named {names}")
            pd = g.GetPointData()
            for i in range(pd.GetNumberOfArrays()):
                a = pd.GetArray(i)
                types.setdefault(("point", a.GetName()), set()).add(
                    (a.GetDataTypeAsString(), a.GetNumberOfComponents()))
            # meshio
            out, err = io.StringIO(), io.StringIO()
            try:
                with warnings.catch_warnings(record=True) as w, contextlib.redirect_stdout(out), \
                        contextlib.redirect_stderr(err):
                    warnings.simplefilter("always")
                    m = meshio.read(path)
                if w or out.getvalue().strip() or err.getvalue().strip() or log.getvalue().strip():
                    errors.append(f"{name}: meshio says: {[str(x.message) for x in w]} "
                                  f"{out.getvalue()} {err.getvalue()} {log.getvalue()}"[:300])
                    log.truncate(0)
                ncm = sum(len(c.data) for c in m.cells) - (1 if ours.placeholder else 0)
                if len(m.points) != ours.npoints or ncm != ours.ncells:
                    errors.append(f"{name}: meshio {len(m.points)} points {ncm} cells")
                if abs(float(m.field_data["TimeValue"][0]) - t) > 1e-15 * max(1.0, abs(t)):
                    errors.append(f"{name}: meshio TimeValue {m.field_data['TimeValue']}")
            except BaseException as e:  # meshio may even call sys.exit
                errors.append(f"{name}: meshio failed: {type(e).__name__}: {e}")
            KIND[series] += 1
        for key, ts in types.items():
            if len(ts) != 1:
                errors.append(f"{run}/{series}: array {key} declared as {sorted(ts)} across the series")
        if series == "cracks" and not read_vtu(steps[0][1]).placeholder:
            errors.append(f"{run}: the t = 0 crack file is not the empty-grid placeholder")
if errors:
    print("\n".join(errors))
    sys.exit(1)
print(f"VTK and meshio read {KIND['fields']} field and {KIND['cracks']} crack files cleanly")
EOT
echo "PASS: test_vtu_readers (${SECONDS} s)"
