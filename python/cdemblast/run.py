"""One run directory as `cdemblast run` writes it (docs/case_reference.md, section 6).

Every file is optional: a missing or unreadable one is None / empty, with a note in
`Run.notes`. A CSV cut short by an interrupted run loses only its incomplete last line.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re

import numpy as np

from . import vtu
from .vtu import VTK_TETRA, VtuError

try:
    import tomllib
except ImportError:  # Python < 3.11: the resolved case is not read
    tomllib = None


# ----------------------------------------------------------------------------- tables
def read_table(path):
    """{column: np.array} (floats; text columns stay lists of str), or None if the file is
    missing or has no data row."""
    if not os.path.isfile(path):
        return None
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        return None
    header = [h.strip() for h in rows[0]]
    cols = {h: [] for h in header}
    for r in rows[1:]:
        if len(r) != len(header):
            continue  # a truncated last line of an interrupted run
        for h, v in zip(header, r):
            cols[h].append(v)
    out = {}
    for h, vals in cols.items():
        try:
            out[h] = np.array([float(v) for v in vals])
        except ValueError:
            out[h] = vals
    if not any(len(v) for v in out.values()):
        return None
    return out


def read_history(path):
    """A time history table (read_table with a numeric time column), or None."""
    out = read_table(path)
    if not out or not isinstance(out.get("time"), np.ndarray) or out["time"].size == 0:
        return None
    return out


def split_by(table, key):
    """{value of column `key`: {column: np.array}} in order of appearance (numeric columns)."""
    if not table or key not in table:
        return {}
    names = table[key]
    order = list(dict.fromkeys(names))
    names = np.array(names)
    return {n: {k: v[names == n] for k, v in table.items() if isinstance(v, np.ndarray)}
            for n in order}


def read_monitors(path):
    """{monitor name: {column: np.array}} in order of appearance, or {}."""
    return split_by(read_history(path), "monitor")


def read_toml(path):
    """A TOML file as a dict ({} when missing or unreadable)."""
    if tomllib is None or not os.path.isfile(path):
        return {}
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except (OSError, ValueError):
        return {}


def finite(v):
    """v as a float when it is a finite number, else None."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    return float(v) if math.isfinite(v) else None


# ----------------------------------------------------------------------------- the run
RUN_ID_RE = re.compile(r"cdemblast:? run_id ([0-9a-f]+)")


def run_ids(path):
    """{output file: run id} of a run directory: summary.json's "run_id", and the id that
    fields.pvd, cracks.pvd (an XML comment) and case.resolved.toml (its first line) carry.
    Files without an id (older runs) are left out."""
    ids = {}
    try:
        with open(os.path.join(path, "summary.json")) as f:
            rid = json.load(f).get("run_id")
        if isinstance(rid, str) and rid:
            ids["summary.json"] = rid
    except (OSError, ValueError, AttributeError):
        pass
    for name in ("fields.pvd", "cracks.pvd", "case.resolved.toml"):
        try:
            with open(os.path.join(path, name), errors="replace") as f:
                head = f.read(4096)
        except OSError:
            continue
        m = RUN_ID_RE.search(head)
        if m:
            ids[name] = m.group(1)
    return ids


def mixed_run_ids(path):
    """A message when the outputs of `path` carry different run ids (two runs wrote into it),
    else None."""
    ids = run_ids(path)
    if len(set(ids.values())) <= 1:
        return None
    return "its outputs belong to different runs: " + ", ".join(
        f"{k} has run {v}" for k, v in sorted(ids.items()))


class Run:
    """Everything the report and the studies read from one run directory."""

    def __init__(self, path, label=None):
        self.dir = os.path.abspath(path)
        self.notes = []
        self.summary = {}
        sp = os.path.join(self.dir, "summary.json")
        if os.path.isfile(sp):
            try:
                with open(sp) as f:
                    self.summary = json.load(f)
            except (OSError, ValueError) as e:
                self.notes.append(f"summary.json could not be read ({e}).")
        else:
            self.notes.append("summary.json is missing (the run may not have finished).")
        self.label = label or str(self.summary.get("title") or os.path.basename(self.dir.rstrip("/")))
        self.case = read_toml(os.path.join(self.dir, "case.resolved.toml"))
        self.energy = read_history(os.path.join(self.dir, "energy.csv"))
        self.fracture = read_history(os.path.join(self.dir, "fracture.csv"))
        self.monitors = read_monitors(os.path.join(self.dir, "monitors.csv"))
        self.charges = split_by(read_history(os.path.join(self.dir, "charges.csv")), "hole")
        self.fields = self._series("fields.pvd")
        self.cracks = self._series("cracks.pvd")
        self._dim = None

    def _series(self, name):
        try:
            steps = vtu.read_pvd(os.path.join(self.dir, name))
        except VtuError as e:
            self.notes.append(f"{name} could not be read ({e}).")
            return []
        return [(t, p) for t, p in steps if os.path.isfile(p)]

    # ---- the case ----
    @property
    def monitor_points(self):
        """{monitor name: point} from the resolved case."""
        return {m["name"]: m.get("point") for m in self.case.get("monitor", []) if "name" in m}

    @property
    def up(self):
        """The free-surface normal (analysis.up of the case), default +z (3D) or +y (2D)."""
        up = self.case.get("analysis", {}).get("up")
        if isinstance(up, list) and up and all(isinstance(c, (int, float)) for c in up):
            u = np.zeros(3)
            u[:min(3, len(up))] = np.asarray(up[:3], float)
            if np.all(np.isfinite(u)) and np.linalg.norm(u) > 0:
                return u / np.linalg.norm(u)
        return np.array([0.0, 1.0, 0.0]) if self.dim == 2 else np.array([0.0, 0.0, 1.0])

    @property
    def dim(self):
        """2 or 3: from the cell types of a field file, else from the case's mesh size."""
        if self._dim is None:
            for _, path in reversed(self.fields):
                try:
                    g = vtu.read_vtu(path)
                    self._dim = 3 if np.any(g.types == VTK_TETRA) else 2
                    break
                except VtuError:
                    continue
        if self._dim is None:
            size = self.case.get("mesh", {}).get("generate", {}).get("size")
            shape = self.case.get("mesh", {}).get("generate", {}).get("shape")
            if shape == "rectangle" or (isinstance(size, list) and len(size) >= 3 and size[2] == 0):
                self._dim = 2
            elif shape in ("box", "cylinder"):
                self._dim = 3
        return self._dim

    @property
    def per_metre(self):
        """True for a plane-strain (2D) run: volumes, masses and energies are per metre."""
        return self.dim == 2

    def cracks_at(self, t):
        """The crack file written with the field file of time t (None if there is none)."""
        best = None
        for tc, p in self.cracks:
            if abs(tc - t) <= 1e-9 * max(abs(t), 1e-12) + 1e-15:
                best = p
        return best

    def fragments_at(self, field_path):
        """fragments/fragments_NNNN.csv of a field file (same NNNN) as a table, or None."""
        base = os.path.basename(field_path)
        if not base.startswith("fields_"):
            return None
        name = "fragments_" + base[len("fields_"):].rsplit(".", 1)[0] + ".csv"
        return read_table(os.path.join(self.dir, "fragments", name))

    def grading_table(self):
        return read_table(os.path.join(self.dir, "grading.csv"))

    @property
    def finished(self):
        return self.summary.get("status") == "finished"

    def value(self, key):
        """A finite number of summary.json, else None."""
        return finite(self.summary.get(key))


def unique_labels(runs):
    """Runs sharing a label are told apart by their directory names (then by position)."""
    counts = {}
    for r in runs:
        counts[r.label] = counts.get(r.label, 0) + 1
    for r in runs:
        if counts[r.label] > 1:
            r.label = f"{r.label} [{os.path.basename(r.dir)}]"
    seen = set()
    for i, r in enumerate(runs):
        if r.label in seen:
            r.label = f"{r.label} #{i + 1}"
        seen.add(r.label)
    return runs
