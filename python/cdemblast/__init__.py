"""cdemblast's Python side: read run directories and VTU files, draw plots, write the run
report and compare the runs of a study.

Modules (see docs/report.md and docs/study.md):

    vtu         VTU/PVD reader (numpy + zlib + xml.etree; no VTK needed)
    run         one run directory: summary.json, the CSV histories, the resolved case, fields
    geometry    field frames: 2D polygons, 3D sections and top views, cell sizes and volumes
    plots       the pictures shared by the report and the studies
    setup       the model set-up: charges (kg, J), powder factor, element sizes, set-up picture
    checks      the measured warnings of a run
    yardsticks  Kuz-Ram / Swebrec fragment sizes and the PPV-scaled-distance fit
    report      the run report (scripts/cdem_report.py, `cdemblast report`)
    study       studies: variants of a base case, run and compared (`cdemblast study`)
    analyses    study analyses of the shipped examples (SPEC 5.1, 5.2)
    overlap     nodes inside a block of another fragment (contact checks; needs scipy)
    perf        the cost-growth curve from `cdemblast bench --json` reports

The thin commands (scripts/cdem_report.py, scripts/cdem_study.py, examples/*/compare,
examples/multihole_3d/speedup) put this directory's parent on sys.path and import it; no
installation is needed. Needs numpy and matplotlib (Debian: /usr/bin/python3 with
python3-numpy and python3-matplotlib) and Python >= 3.11 (tomllib).
"""

import sys

try:  # the commands' one dependency check (numpy and matplotlib), with the fix in the message
    import matplotlib
    import numpy

    del matplotlib, numpy
except ImportError as _e:
    sys.exit(f"cdemblast: {_e}; run it with a python3 that has numpy and matplotlib (Debian: "
             "/usr/bin/python3 with python3-numpy and python3-matplotlib)")

__all__ = ["vtu", "run", "geometry", "plots", "setup", "checks", "yardsticks", "report", "study", "overlap"]
