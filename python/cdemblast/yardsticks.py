"""The blasting engineer's yardsticks, to put beside the simulated results.

Fragment size (Kuz-Ram and Swebrec)
-----------------------------------
- Median size, Kuznetsov's equation as adapted by Cunningham (Kuz-Ram):
      x50 = A K^-0.8 Q^(1/6) (115 / RWS)^(19/30)      [cm]
  A rock factor (0.8-22; 7 medium, 10 hard fissured, 13 hard weakly fissured rock),
  K powder factor (kg/m3), Q charge per hole (kg), RWS weight strength relative to ANFO
  (ANFO 100, TNT 115).
  Cunningham, C.V.B. (1983). The Kuz-Ram model for prediction of fragmentation from blasting.
  Proc. 1st Int. Symp. on Rock Fragmentation by Blasting, Lulea, 439-453.
  Cunningham, C.V.B. (1987). Fragmentation estimations and the Kuz-Ram model - four years on.
  Proc. 2nd Int. Symp. on Rock Fragmentation by Blasting, Keystone, 475-487.
  Kuznetsov, V.M. (1973). The mean diameter of the fragments formed by blasting rock. Soviet
  Mining Science 9(2), 144-148 (eq. 12: the strength term theta^(-19/30)).
  The exponent of 115/RWS is a parameter: 19/30 as in the 1983 and 1987 papers; Cunningham
  (2005, "The Kuz-Ram fragmentation model - 20 years on", Brighton Conf. Proc., EFEE, 201-210)
  prints 19/20.
- Uniformity index (Cunningham 1987), one explosive in the hole:
      n = (2.2 - 14 B/d) sqrt((1 + S/B) / 2) (1 - W/B) (L/H) P
  B burden (m), S spacing (m), d hole diameter (mm), W standard deviation of the drilling
  accuracy (m), L charge length (m), H bench height (m), P = 1 for a square pattern, 1.1
  staggered.
- Rosin-Rammler with x50 the median (Cunningham 1987): P(x) = 1 - exp(-ln 2 (x / x50)^n).
- Swebrec (Ouchterlony, F. (2005). The Swebrec function: linking fragmentation by blasting and
  crushing. Mining Technology (Trans. IMM A) 114, A29-A44):
      P(x) = 1 / (1 + [ln(xmax / x) / ln(xmax / x50)]^b),  0 < x < xmax,
  with the KCO model's link to Kuz-Ram (same paper): b = 2 ln 2 ln(xmax / x50) n, and xmax the
  in-situ block size or the smaller of burden and spacing.

Ground vibration: peak particle velocity against scaled distance
---------------------------------------------------------------
      PPV = K (R / sqrt(Q))^(-beta)
  (square-root scaling, the form of the US Bureau of Mines: Duvall, W.I. and Petkof, B.
  (1959). Spherical propagation of explosion-generated strain pulses in rock. USBM RI 5483;
  Siskind, D.E. et al. (1980). Structure response and damage produced by ground vibration from
  surface mine blasting. USBM RI 8507). R the distance from the charge (m), Q the largest
  charge per delay (kg; decks fired within `delay_window` of each other count together, 8 ms
  by the usual practice). K and beta are fitted by least squares on log PPV = log K - beta
  log SD. In plane strain the charge is per metre: SD = R / sqrt(Q per metre), m/(kg/m)^0.5.
"""

from __future__ import annotations

import math

import numpy as np

LN2 = math.log(2.0)


# ----------------------------------------------------------------------------- Kuz-Ram
def kuznetsov_x50(rock_factor, powder_factor, charge_per_hole, rws=100.0, rws_exponent=19 / 30):
    """Median fragment size x50 (m) of the Kuz-Ram model (the equation gives cm)."""
    if not (rock_factor > 0 and powder_factor > 0 and charge_per_hole > 0 and rws > 0):
        raise ValueError("Kuz-Ram needs a positive rock factor, powder factor, charge and RWS")
    cm = (rock_factor * powder_factor ** -0.8 * charge_per_hole ** (1 / 6)
          * (115.0 / rws) ** rws_exponent)
    return cm / 100.0


def uniformity_index(burden, spacing, diameter, charge_length, bench_height,
                     drill_deviation=0.0, staggered=False):
    """Cunningham's (1987) uniformity index n (one explosive); diameter in m (the formula
    takes mm)."""
    d_mm = diameter * 1000.0
    n = ((2.2 - 14.0 * burden / d_mm) * math.sqrt((1.0 + spacing / burden) / 2.0)
         * (1.0 - drill_deviation / burden) * (charge_length / bench_height))
    return n * (1.1 if staggered else 1.0)


def rosin_rammler(x, x50, n):
    """Cumulative fraction passing (0-1) of the Rosin-Rammler curve with median x50."""
    x = np.asarray(x, float)
    return 1.0 - np.exp(-LN2 * np.power(np.clip(x, 0, None) / x50, n))


def swebrec_b(x50, xmax, n):
    """The KCO model's Swebrec curvature b from the Kuz-Ram uniformity index n."""
    return 2.0 * LN2 * math.log(xmax / x50) * n


def swebrec(x, x50, xmax, b):
    """Cumulative fraction passing (0-1) of the Swebrec function: 0 at x -> 0, 1/2 at x50,
    1 from xmax on."""
    x = np.asarray(x, float)
    out = np.ones_like(x)
    inside = (x > 0) & (x < xmax)
    f = np.log(xmax / x[inside]) / math.log(xmax / x50)
    out[inside] = 1.0 / (1.0 + f ** b)
    out[x <= 0] = 0.0
    return out


def size_at(passing, x50, n, model="rosin_rammler", xmax=None, b=None):
    """The size (m) at a fraction passing (0-1) of either curve."""
    p = float(passing)
    if model == "rosin_rammler":
        return x50 * (-math.log(1.0 - p) / LN2) ** (1.0 / n)
    # Swebrec inverted: ln(xmax/x) = ln(xmax/x50) ((1 - p) / p)^(1/b)
    return xmax * math.exp(-math.log(xmax / x50) * ((1.0 - p) / p) ** (1.0 / b))


class KuzRam:
    """A Kuz-Ram / Swebrec prediction for a design.

    design keys (m, kg, kg/m3): rock_factor, burden, spacing, bench_height, hole_diameter,
    charge_length, charge_per_hole; optional powder_factor (default charge_per_hole /
    (burden x spacing x bench_height)), rws (100), rws_exponent (19/30), drill_deviation (0),
    staggered (false), xmax (default min(burden, spacing))."""

    REQUIRED = ("rock_factor", "burden", "spacing", "bench_height", "hole_diameter",
                "charge_length", "charge_per_hole")

    def __init__(self, design):
        missing = [k for k in self.REQUIRED if not isinstance(design.get(k), (int, float))]
        if missing:
            raise ValueError("the Kuz-Ram design needs " + ", ".join(missing))
        d = {k: float(v) for k, v in design.items() if isinstance(v, (int, float))
             and not isinstance(v, bool)}
        self.design = dict(design)
        self.q = d["charge_per_hole"]
        self.k = d.get("powder_factor") or self.q / (d["burden"] * d["spacing"] * d["bench_height"])
        self.rws = d.get("rws", 100.0)
        self.x50 = kuznetsov_x50(d["rock_factor"], self.k, self.q, self.rws,
                                 d.get("rws_exponent", 19 / 30))
        self.n = uniformity_index(d["burden"], d["spacing"], d["hole_diameter"],
                                  d["charge_length"], d["bench_height"],
                                  d.get("drill_deviation", 0.0), bool(design.get("staggered")))
        self.xmax = d.get("xmax") or min(d["burden"], d["spacing"])
        self.b = swebrec_b(self.x50, self.xmax, self.n) if self.xmax > self.x50 else None

    def passing(self, x, model="rosin_rammler"):
        """% passing at sizes x (m)."""
        if model == "swebrec":
            if self.b is None:
                return None
            return 100.0 * swebrec(x, self.x50, self.xmax, self.b)
        return 100.0 * rosin_rammler(x, self.x50, self.n)

    def d(self, pct, model="rosin_rammler"):
        if model == "swebrec" and self.b is None:
            return None
        return size_at(pct / 100.0, self.x50, self.n, model, self.xmax, self.b)

    def to_json(self):
        return {"powder_factor_kg_m3": self.k, "charge_per_hole_kg": self.q, "rws": self.rws,
                "x50_m": self.x50, "uniformity_n": self.n, "xmax_m": self.xmax,
                "swebrec_b": self.b,
                "rosin_rammler": {f"d{p}_m": self.d(p) for p in (10, 20, 40, 50, 80, 90)},
                "swebrec": ({f"d{p}_m": self.d(p, "swebrec") for p in (10, 20, 40, 50, 80, 90)}
                            if self.b is not None else None),
                "inputs": self.design}


# ----------------------------------------------------------------------------- PPV
def fit_ppv(scaled_distance, ppv):
    """Least-squares fit of PPV = K SD^-beta on log-log axes.

    Returns {"K", "beta", "r2", "points"}; None with fewer than two distinct distances."""
    sd = np.asarray(scaled_distance, float)
    v = np.asarray(ppv, float)
    ok = np.isfinite(sd) & np.isfinite(v) & (sd > 0) & (v > 0)
    sd, v = sd[ok], v[ok]
    if np.unique(sd).size < 2:
        return None
    x, y = np.log(sd), np.log(v)
    slope, intercept = np.polyfit(x, y, 1)
    pred = intercept + slope * x
    ss = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - float(np.sum((y - pred) ** 2)) / ss if ss > 0 else 1.0
    return {"K": float(math.exp(intercept)), "beta": float(-slope), "r2": r2,
            "points": int(sd.size)}


def pad3(v):
    """A point of 2 or 3 coordinates as a 3-vector (z = 0 in 2D)."""
    out = np.zeros(3)
    v = np.asarray(v, float).ravel()[:3]
    out[:v.size] = v
    return out


def distance_to_segment(p, a, b):
    """Distance (m) of the point p to the segment a-b (2 or 3 coordinates)."""
    p, a, b = (pad3(v) for v in (p, a, b))
    d = b - a
    s = float(np.clip(np.dot(p - a, d) / max(float(np.dot(d, d)), 1e-300), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + s * d)))


def charge_per_delay(decks, window=8e-3):
    """The largest mass (kg) fired within `window` seconds: decks sorted by delay are grouped
    while each starts less than `window` after the group's first."""
    ds = sorted((d["delay_s"], d["mass_kg"]) for d in decks if d.get("mass_kg"))
    best, i = 0.0, 0
    while i < len(ds):
        t0, tot, j = ds[i][0], 0.0, i
        while j < len(ds) and ds[j][0] < t0 + window:
            tot += ds[j][1]
            j += 1
        best = max(best, tot)
        i += 1
    return best or None


def monitor_ppv(run, decks, window=8e-3):
    """[{monitor, point, ppv_m_s, time_s, distance_m, scaled_distance}] of a run: the peak
    of the velocity magnitude at each monitor, its distance to the nearest charge deck (the
    charged part of the hole axis) and the scaled distance R / sqrt(Q), Q the largest charge
    per delay."""
    q = charge_per_delay(decks, window)
    pts = run.monitor_points
    out = []
    for name, m in run.monitors.items():
        comps = [m[c] for c in ("vx", "vy", "vz") if c in m]
        if not comps or name not in pts or not decks:
            continue
        speed = np.sqrt(sum(c * c for c in comps))
        i = int(np.nanargmax(speed))
        p = np.zeros(3)
        p[:len(pts[name][:3])] = pts[name][:3]
        r = min(distance_to_segment(p, d["start"], d["stop"]) for d in decks)
        out.append({"monitor": name, "point": [float(c) for c in p], "ppv_m_s": float(speed[i]),
                    "time_s": float(m["time"][i]), "distance_m": r,
                    "scaled_distance": r / math.sqrt(q) if q else None})
    return out, q
