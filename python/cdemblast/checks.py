"""Warnings that matter, each measured on the run (issue 18): the report shows them in a box at
the top and writes them into report.json as `warnings`; warnings the run itself wrote into
summary.json (`warnings`, a list of strings or of {"code", "message"}) are merged in.

Every warning is a dict {"code", "message", "value", "limit"}; docs/report.md lists the codes,
what each measures and its limit.
"""

from __future__ import annotations

import numpy as np

from .plots import last_frame
from .run import finite

DAMAGED = 0.5             # a block counts as damaged from this damage (broken area share) on
ENERGY_ERROR_LIMIT = 0.01  # relative energy balance error
POWDER_FACTOR_RANGE = (0.1, 3.0)  # kg/m3
GRADING_SIZES = 2.0        # d50 within this many block sizes: the grading is the mesh
WAVE_ENERGY_LEFT = 0.05    # share of the energy put in still in the waves


def warning(code, message, value=None, limit=None):
    return {"code": code, "message": message, "value": value, "limit": limit}


# ----------------------------------------------------------------------------- boundaries
def side_cells(setup, frame):
    """{face set name: cell mask of the blocks touching it} for generated shapes (the sides of
    a rectangle, box or cylinder; docs/case_reference.md 3.2), {} otherwise."""
    gen = setup.case.get("mesh", {}).get("generate")
    if not isinstance(gen, dict):
        return {}
    X, grid = frame.X, frame.grid
    lo, hi = X.min(0), X.max(0)
    tol = 1e-6 * float(np.max(hi - lo) or 1.0)
    from .geometry import cell_node_lists
    masks = {}

    def touching(on_node):
        m = np.zeros(grid.ncells, bool)
        for ids, nodes in cell_node_lists(grid):
            m[ids] = on_node[nodes].any(1)
        return m

    shape = gen.get("shape")
    if shape == "rectangle":
        sides = {"left": (0, lo[0]), "right": (0, hi[0]), "bottom": (1, lo[1]), "top": (1, hi[1])}
    elif shape == "box":
        sides = {"left": (0, lo[0]), "right": (0, hi[0]), "front": (1, lo[1]),
                 "back": (1, hi[1]), "bottom": (2, lo[2]), "top": (2, hi[2])}
    elif shape == "cylinder":
        sides = {"bottom": (2, lo[2]), "top": (2, hi[2])}
        c = np.zeros(3)
        o = gen.get("origin", [0, 0, 0])
        c[:len(o[:3])] = o[:3]
        r = np.hypot(X[:, 0] - c[0], X[:, 1] - c[1])
        masks["side"] = touching(r >= r.max() - max(tol, 1e-3 * r.max()))
    else:
        return {}
    for name, (axis, level) in sides.items():
        masks[name] = touching(np.abs(X[:, axis] - level) <= tol)
    return masks


def boundary_damage(setup, frame):
    """[(face set, type, damaged blocks, blocks)] of the fixed, roller and non-reflecting face
    sets whose blocks are damaged at this frame."""
    masks = side_cells(setup, frame)
    dmg = frame.cell("damage")
    if not masks or dmg is None:
        return []
    dmg = np.asarray(dmg, float)
    rock = ~setup.charge_cell
    out = []
    for b in setup.case.get("boundary", []):
        name, kind = b.get("faces"), b.get("type")
        if kind not in ("fixed", "roller", "non_reflecting") or name not in masks:
            continue
        m = masks[name] & rock
        n = int(np.sum(m & (dmg >= DAMAGED)))
        if n:
            out.append((name, kind, n, int(m.sum())))
    return out


# ----------------------------------------------------------------------------- the checks
def energy_at(run, t):
    """{column: value} of the energy.csv row nearest to t, or None."""
    e = run.energy
    if e is None:
        return None
    i = int(np.argmin(np.abs(e["time"] - t)))
    return {k: float(v[i]) for k, v in e.items() if isinstance(v, np.ndarray)}


def measure(run, setup):
    """(warnings, numbers): every check of the run; numbers holds what each one measured."""
    warns, numbers = [], {}
    s = run.summary
    last = last_frame(run, 1.0, []) if run.fields else None

    # Damage reached a fixed or absorbing boundary: the model is too small for the blast.
    if last is not None and setup.measures is not None:
        hits = boundary_damage(setup, last)
        numbers["boundary_damage"] = [
            {"faces": n, "type": k, "damaged_blocks": d, "blocks": t} for n, k, d, t in hits]
        for name, kind, n, tot in hits:
            what = "fixed" if kind == "fixed" else "roller" if kind == "roller" else "absorbing"
            warns.append(warning(
                "damage_at_boundary",
                f"damage reached the {what} boundary '{name}' ({kind}): {n} of its {tot} blocks "
                f"have damage >= {DAMAGED} at t = {last.time * 1e3:.3g} ms. The model is too small "
                "for the blast: the boundary, not the rock mass, decides the result there.",
                n, 0))
        if not side_cells(setup, last) and setup.case.get("mesh", {}).get("file"):
            numbers["boundary_damage_note"] = ("mesh file: the face sets' geometry is not in the "
                                               "run directory, the boundary check is skipped")

    # Grading limited by the element size.
    d50 = finite(s.get("d50_m"))
    sizes = setup.element_sizes()
    h = sizes.get("block_size_median_m")
    if d50 is not None and h:
        numbers["d50_over_block_size"] = d50 / h
        if d50 <= GRADING_SIZES * h:
            warns.append(warning(
                "grading_is_mesh",
                f"the fragment grading is limited by the element size: d50 = {d50:.3g} m is within "
                f"{GRADING_SIZES:g} block sizes (the median block alone measures L_bc = {h:.3g} m, "
                f"the finest fragment the mesh can resolve). Most fragments are single blocks: "
                "refine the mesh to measure the grading.", d50 / h, GRADING_SIZES))

    # Energy error.
    err = finite(s.get("energy_error"))
    if err is None and run.energy is not None and "error" in run.energy:
        err = float(run.energy["error"][-1])
    if err is not None:
        numbers["energy_error"] = err
        if err > ENERGY_ERROR_LIMIT:
            warns.append(warning(
                "energy_error",
                f"the energy balance error is {100 * err:.2g} % (above {100 * ENERGY_ERROR_LIMIT:g} "
                "%): the run is not to be trusted without a smaller time step or a finer mesh.",
                err, ENERGY_ERROR_LIMIT))

    # Powder factor.
    k, _ = setup.powder_factor()
    if k is not None:
        numbers["powder_factor_kg_m3"] = k
        lo, hi = POWDER_FACTOR_RANGE
        if not lo <= k <= hi:
            per = " (2D: per metre of charge over per metre of rock)" if setup.per_metre else ""
            warns.append(warning(
                "powder_factor",
                f"the powder factor is {k:.3g} kg/m³{per}, outside the usual {lo:g}-{hi:g} kg/m³ of "
                f"rock blasting: {'far more charge than such rock needs (expect pulverisation)' if k > hi else 'too little charge to break such rock'}.",
                k, [lo, hi]))

    # The blast reached a damping zone with energy left in the waves.
    if setup.measures is not None and setup.damping_cell.any() and run.fields:
        from .plots import load_frames
        t_reach = None
        for i in range(len(run.fields)):
            fr = load_frames(run, [i], 1.0, [])
            if not fr:
                continue
            d = fr[0].cell("damage")
            if d is not None and np.any(np.asarray(d)[setup.damping_cell] >= DAMAGED):
                t_reach = fr[0].time
                break
        if t_reach is not None:
            e = energy_at(run, t_reach)
            if e:
                wave = e.get("kinetic", 0) + e.get("block_strain", 0) + e.get("spring_strain", 0)
                put = (e.get("explosive_work", 0) + e.get("external_work", 0)
                       + e.get("gravity_work", 0) + e.get("initial", 0) + e.get("insertion", 0))
                share = wave / put if put > 0 else None
                numbers["damping_zone"] = {"time_s": t_reach, "wave_energy_share": share}
                if share is not None and share > WAVE_ENERGY_LEFT:
                    warns.append(warning(
                        "damping_zone_reached",
                        f"the blast reached the damping zone ({', '.join(setup.damping)}) at "
                        f"t = {t_reach * 1e3:.3g} ms with {100 * share:.0f} % of the energy put in "
                        "still in the waves (kinetic + strain): the zone absorbs energy that would "
                        "break and throw rock; move it further out.", share, WAVE_ENERGY_LEFT))

    # A charge larger than the blocks it runs through (per block).
    for p, mx, n_over, _ids, _share in setup.max_charge_share():
        numbers.setdefault("charge_share", []).append(
            {"hole": p["hole"], "deck": p["deck"], "max_share": mx, "blocks_over_1": n_over})
        if n_over:
            warns.append(warning(
                "charge_larger_than_block",
                f"hole '{p['hole']}' deck {p['deck']}: the charge is larger than {n_over} of the "
                f"blocks it runs through (charge volume / block volume up to {mx:.2f}). Mesh the "
                "rock with elements at least as large as the hole (the bar model's premise).",
                mx, 1.0))

    # Run state.
    if s and s.get("status") not in (None, "finished"):
        warns.insert(0, warning("status", f"the run did not finish: status '{s.get('status')}'"
                                + (f" ({s.get('diagnosis')})" if s.get("diagnosis") else "")))
    return merge(warns, s.get("warnings")), numbers


def merge(ours, theirs):
    """Our warnings plus those of summary.json (strings or dicts), without repeating a code."""
    out = list(ours)
    codes = {w["code"] for w in ours}
    for w in theirs if isinstance(theirs, list) else []:
        if isinstance(w, str):
            out.append(warning("run", w))
        elif isinstance(w, dict) and w.get("message"):
            code = str(w.get("code", "run"))
            if code in codes and code != "run":
                continue  # measured here too: keep one
            out.append(warning(code, str(w["message"]), w.get("value"), w.get("limit")))
    return out

