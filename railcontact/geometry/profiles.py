"""Wheel and rail profiles: built-in standard profiles, file readers, smooth interpolation.

Conventions (SI, each profile in its own frame; the track frame is made in ``track.py``):

* ``y`` is lateral, **positive towards the field side** (away from the track centre), for
  wheel and rail alike, so one profile serves the left and the right side.
* Wheel (``kind = "wheel"``): ``y = 0`` at the taping line (the nominal rolling circle,
  70 mm from the flange back for S1002); ``z`` is the radius increment over the nominal
  radius (positive = larger radius, towards the rail). The flange is at ``y < 0``.
* Rail (``kind = "rail"``): ``y = 0`` at the crown of the uncanted rail (its axis); ``z``
  is the height, positive up, 0 at the crown. Built-in rails are uncanted; the track
  applies the inclination. A file rail may be canted already (then give inclination 0).

Built-in profiles
-----------------
``S1002``  EN 13715 / UIC 510-2 section formulas (coefficients as DLR's ``s1002`` function,
           ``docs/algorithms.md`` Sec. 7.1), S from -70 (flange back) to +60 mm.
``60E1``   (alias ``UIC60``) EN 13674-1 head: R300 crown to ``|y|`` = 10.228 mm, tangent R80 to
           ``|y|`` = 26.0265 mm, tangent R13 until the 1:20 flank direction, then the flank
           (transcription of the standard in ``docs/algorithms.md`` Sec. 7.2a).
``CN60``   (aliases ``CHN60``, ``60KG``) Chinese 60 kg/m rail (TB/T 2344, GB 2585): tangent
           arcs R300 (crown, to ``|y|`` = 10 mm) - R80 - R13, the R13 meeting a 1:20 head side
           at ``|y|`` = 35.4 mm (70.8 mm across), the side running down until the head is
           73 mm wide (its widest point, 36.2 mm below the crown). Cited: the radii and
           the 73 mm head width (section data); the two extents (10 and 35.4 mm) and the
           1:20 side are those of the only public description found, the rail-grinding
           code ``helayht/grind_car`` (``StandardRailProfileSolver.cs``), not the
           drawing; the tangent points are derived (``_cn60``). ``S1002CN`` is S1002.

Interpolation: a C^2 cubic spline through the points (exact for the built-ins, which are
sampled every 0.05 mm from their definitions); height, slope and curvature follow from it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import RailContactError
from ..formed import FormedOnce
from .spline import evaluate

KINDS = ("wheel", "rail")
MAX_PROFILE_SPAN = 1.0
"""Largest extent [m] of a plausible wheel or rail profile (a larger one has a wrong unit)."""
MIN_PROFILE_SPAN = 0.02
"""Smallest lateral extent [m] of a plausible profile file (a rail's head is 70 mm wide,
a wheel's tread and flange 130 mm: a smaller one has a wrong unit)."""


@dataclass(frozen=True)
class Profile:
    """A wheel or rail profile z(y) [m]; see the module docstring for the frames.

    Parameters
    ----------
    y, z
        Points [m], ``y`` strictly increasing.
    kind
        ``"wheel"`` or ``"rail"``.
    name
        For messages and plots.
    """

    y: np.ndarray
    z: np.ndarray
    kind: str
    name: str = "profile"
    _spline: CubicSpline = field(init=False, repr=False, compare=False)
    _pieces: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise RailContactError(f"profile kind must be one of {KINDS}, got {self.kind!r}")
        y = np.asarray(self.y, dtype=float)
        z = np.asarray(self.z, dtype=float)
        if y.ndim != 1 or y.shape != z.shape:
            raise RailContactError(f"profile {self.name!r}: y and z must be 1-D of equal length")
        if y.size < 4:
            raise RailContactError(f"profile {self.name!r} has {y.size} points; at least 4 "
                                   "are needed")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
            raise RailContactError(f"profile {self.name!r} contains NaN or infinite values")
        span = max(float(y.max() - y.min()), float(np.abs(z).max()))
        if span > MAX_PROFILE_SPAN:
            raise RailContactError(
                f"profile {self.name!r} spans {span:.3g} m; a wheel or rail profile spans "
                f"about 0.1-0.2 m (at most {MAX_PROFILE_SPAN} m): is its unit right (a "
                "two-column file in mm needs profile_unit = 'mm')?")
        dy = np.diff(y)
        if not np.all(dy > 0):
            k = int(np.argmax(dy <= 0))
            raise RailContactError(
                f"profile {self.name!r}: y must increase strictly (point {k + 1} at "
                f"y = {y[k + 1]:.6g} m follows y = {y[k]:.6g} m); a profile that folds back "
                "on itself cannot be described as z(y)")
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "z", z)
        spline = CubicSpline(y, z, bc_type="not-a-knot")
        object.__setattr__(self, "_spline", spline)
        # its breakpoints and coefficients, read once (scipy's properties convert them on
        # every access, which costs more than evaluating a short array)
        object.__setattr__(self, "_pieces", (spline.x, spline.c))

    @property
    def bounds(self) -> tuple[float, float]:
        """Lateral extent (y_min, y_max) [m]."""
        return float(self.y[0]), float(self.y[-1])

    def height(self, y: np.ndarray | float) -> np.ndarray:
        """z(y) [m] (radius increment for a wheel, height for a rail)."""
        out = evaluate(*self._pieces, y, 0)  # compiled, for long arrays
        return self._spline(y) if out is None else out

    def samples(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """``n`` equally spaced points (y, z(y)) over the profile's extent [m], computed once
        per ``n`` (read-only arrays)."""
        return _formed.get(self, _form_samples, n)

    def slope(self, y: np.ndarray | float) -> np.ndarray:
        """dz/dy [-]."""
        out = evaluate(*self._pieces, y, 1)
        return self._spline(y, 1) if out is None else out

    def curvature(self, y: np.ndarray | float) -> np.ndarray:
        """Signed curvature z'' / (1 + z'^2)^(3/2) [1/m] (positive: z convex downward... i.e.
        the curve bends towards +z)."""
        d1 = self._spline(y, 1)
        return self._spline(y, 2) / (1 + d1 * d1) ** 1.5

    def mirrored(self) -> Profile:
        """The same profile with y -> -y (e.g. a file written with the field side at -y)."""
        return Profile(-self.y[::-1], self.z[::-1], self.kind, self.name)

    def write(self, path: str | Path, unit: str = "mm") -> Path:
        """Write the points as two-column text (y, z) with a header, in ``unit``."""
        f = _unit_factor(unit)
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        header = (f"railcontact {self.kind} profile {self.name}\n"
                  f"columns: y [{unit}] (positive to the field side), z [{unit}] "
                  + ("(radius increment, positive = larger radius)" if self.kind == "wheel"
                     else "(height, positive up, uncanted)"))
        np.savetxt(p, np.column_stack([self.y * f, self.z * f]), fmt="%.6f", header=header)
        return p


def _form_samples(profile: Profile, n: int) -> tuple[np.ndarray, np.ndarray]:
    y = np.linspace(*profile.bounds, n)
    z = profile.height(y)
    y.flags.writeable = z.flags.writeable = False
    return y, z


_formed = FormedOnce()
"""What is formed once per profile (:meth:`Profile.samples`), beside the frozen records."""


# ------------------------------------------------------------------------------ built-ins

_S1002_SECTIONS = [  # (S_from, S_to) in mm, decreasing S, and the function of S
    (60.0, 32.15796, lambda s: 1.364323640 - 0.066666667 * s),
    (32.15796, -26.0, lambda s: np.polyval([2.646656573e-13, -5.957839843e-12, 5.309217349e-15,
                                            -1.562379023e-08, 5.844240864e-08,
                                            -2.810427944e-05, 1.565681624e-03,
                                            -3.358537058e-02, 0.0], s)),
    (-26.0, -35.0, lambda s: -np.polyval([2.252755540e-07, 4.687195829e-05, 4.169739389e-03,
                                          2.054332446e-01, 6.051367875, 1.065501873e+02,
                                          1.038384026e+03, 4.320221063e+03], s)),
    (-35.0, -38.426669071, lambda s: 16.446 - np.sqrt(13.0**2 - (s + 26.210665) ** 2)),
    (-38.426669071, -39.764473993, lambda s: -93.576667419 - 2.747477419 * s),
    (-39.764473993, -49.662510381,
     lambda s: 8.834924130 + np.sqrt(20.0**2 - (s + 58.558326413) ** 2)),
    (-49.662510381, -62.764705882, lambda s: 16.0 + np.sqrt(12.0**2 - (s + 55.0) ** 2)),
    (-62.764705882, -70.0, lambda s: 9.519259302 + np.sqrt(np.clip(20.5**2 - (s + 49.5) ** 2,
                                                                   0, None))),
]


def s1002_radius_increment(s_mm: np.ndarray) -> np.ndarray:
    """EN 13715 S1002 radius increment F(S) [mm] at lateral positions S [mm] in [-70, 60]."""
    s = np.asarray(s_mm, dtype=float)
    out = np.full(s.shape, np.nan)
    for hi, lo, f in _S1002_SECTIONS:
        sel = (s <= hi) & (s >= lo) & np.isnan(out)
        out[sel] = f(s[sel])
    return out


def _s1002() -> Profile:
    s = np.arange(-70.0, 60.0 + 1e-9, 0.05)
    # near the flange back the flank is vertical (dF/dS infinite at S = -70): start just
    # inside so the spline stays well conditioned
    s[0] = -69.95
    s = np.unique(np.concatenate([s, [-69.99]]))
    return Profile(s * 1e-3, s1002_radius_increment(s) * 1e-3, "wheel", "S1002")


def _arc_rail(name: str, y1: float, y2: float, depth: float = 20.0) -> Profile:
    """Rail head from tangent arcs R300 - R80 - R13 and a 1:20 flank [mm in, m out].

    R300 centred below the crown to |y| = y1; R80 tangent to it up to |y| = y2; R13 tangent
    to R80 until the flank direction (1, -20); then the flank down to ``depth`` below the
    crown.
    """
    r1, r2, r3 = 300.0, 80.0, 13.0
    c1 = np.array([0.0, -r1])
    p1 = np.array([y1, -r1 + math.sqrt(r1**2 - y1**2)])
    c2 = p1 + (r2 / r1) * (c1 - p1)

    def r13_part(y2v: float):
        p2 = np.array([y2v, c2[1] + math.sqrt(r2**2 - (y2v - c2[0]) ** 2)])
        c3 = p2 + (r3 / r2) * (c2 - p2)
        n = np.array([20.0, 1.0]) / math.sqrt(401.0)  # outward normal of the 1:20 flank
        p3 = c3 + r3 * n
        return p2, c3, p3

    p2, c3, p3 = r13_part(float(y2))
    y_end = p3[0] + (depth + p3[1]) / 20.0  # flank: z = p3z - 20 (y - p3y)
    yy = np.unique(np.concatenate([
        np.arange(0.0, p3[0], 0.05), np.linspace(p3[0], y_end, 60)]))

    def z_of(y):
        y = np.abs(y)
        return np.where(y <= y1, c1[1] + np.sqrt(r1**2 - y**2),
               np.where(y <= p2[0], c2[1] + np.sqrt(np.clip(r2**2 - (y - c2[0]) ** 2, 0, None)),
               np.where(y <= p3[0], c3[1] + np.sqrt(np.clip(r3**2 - (y - c3[0]) ** 2, 0, None)),
                        p3[1] - 20.0 * (y - p3[0]))))

    y_all = np.concatenate([-yy[:0:-1], yy])
    return Profile(y_all * 1e-3, z_of(y_all) * 1e-3, "rail", name)


CN60_CROWN_HALF_WIDTH = 10.0
"""``|y|`` [mm] where the CN60 crown R300 ends (``helayht/grind_car``; drawing not found)."""
CN60_SIDE_TANGENT_HALF_WIDTH = 35.4
"""``|y|`` [mm] where the CN60 R13 meets the 1:20 head side (``helayht/grind_car``)."""
CN60_HEAD_WIDTH = 73.0
"""Published CN60 head width [mm], its widest point (rail section data)."""


@dataclass(frozen=True)
class ArcHead:
    """Tangent points and arc centres of a R300 - R80 - R13 - 1:20 rail head [mm], uncanted,
    origin at the crown, z up; the side runs from ``side_top`` down to ``side_bottom``."""

    crown_end: tuple[float, float]
    r80_centre: tuple[float, float]
    r80_end: tuple[float, float]
    r13_centre: tuple[float, float]
    side_top: tuple[float, float]
    side_bottom: tuple[float, float]


def cn60_head() -> ArcHead:
    """The CN60 head's tangent points, derived from the radii R300, R80, R13, the crown
    extent, the 1:20 side's tangent point and the 73 mm head width (see the module notes).

    R80's centre lies on the line from the R300 tangent point to R300's centre, 80 mm
    from the point; R13's centre lies 13 mm inside the 1:20 side along its normal and
    67 mm (= 80 - 13) from R80's centre; the R80/R13 tangent point lies on the line of
    the two centres; the side widens at 1:20 until the head is 73 mm wide.
    """
    r1, r2, r3 = 300.0, 80.0, 13.0
    y1 = CN60_CROWN_HALF_WIDTH
    c1 = np.array([0.0, -r1])
    p1 = np.array([y1, -r1 + math.sqrt(r1**2 - y1**2)])
    c2 = p1 + (r2 / r1) * (c1 - p1)
    n = np.array([20.0, 1.0]) / math.sqrt(401.0)  # outward normal of the 1:20 side
    c3y = CN60_SIDE_TANGENT_HALF_WIDTH - r3 * n[0]
    c3 = np.array([c3y, c2[1] + math.sqrt((r2 - r3) ** 2 - (c3y - c2[0]) ** 2)])
    p2 = c2 + r2 * (c3 - c2) / (r2 - r3)
    p3 = c3 + r3 * n
    y_end = CN60_HEAD_WIDTH / 2
    p4 = np.array([y_end, p3[1] - 20.0 * (y_end - p3[0])])
    return ArcHead(*(tuple(map(float, v)) for v in (p1, c2, p2, c3, p3, p4)))


def _cn60() -> Profile:
    """The CN60 head of :func:`cn60_head`, sampled every 0.05 mm on the arcs [m]."""
    h = cn60_head()
    c2, c3 = np.array(h.r80_centre), np.array(h.r13_centre)
    y1, y2, y3 = h.crown_end[0], h.r80_end[0], h.side_top[0]
    yy = np.unique(np.concatenate([np.arange(0.0, y3, 0.05), [y1, y2],
                                   np.linspace(y3, h.side_bottom[0], 100)]))

    def z_of(y):
        y = np.abs(y)
        return np.where(y <= y1, -300.0 + np.sqrt(300.0**2 - y**2),
               np.where(y <= y2, c2[1] + np.sqrt(np.clip(80.0**2 - (y - c2[0]) ** 2, 0, None)),
               np.where(y <= y3, c3[1] + np.sqrt(np.clip(13.0**2 - (y - c3[0]) ** 2, 0, None)),
                        h.side_top[1] - 20.0 * (y - y3))))

    y_all = np.concatenate([-yy[:0:-1], yy])
    return Profile(y_all * 1e-3, z_of(y_all) * 1e-3, "rail", "CN60")


_BUILTIN = {
    "S1002": _s1002,
    "60E1": lambda: _arc_rail("60E1", 10.228, 26.0265),
    "CN60": _cn60,
}
_ALIASES = {"UIC60": "60E1", "S1002CN": "S1002", "60KG": "CN60", "CHN60": "CN60"}


def builtin_profile(name: str) -> Profile:
    """A built-in profile by name: S1002 (S1002CN), 60E1 (UIC60), CN60 (60kg, CHN60)."""
    key = _ALIASES.get(str(name).upper(), str(name).upper())
    if key not in _BUILTIN:
        raise RailContactError(f"unknown built-in profile {name!r}; available: "
                               f"{sorted(_BUILTIN)} (aliases {sorted(_ALIASES)})")
    return _BUILTIN[key]()


# ------------------------------------------------------------------------------ readers

def _unit_factor(unit: str) -> float:
    """Number of ``unit`` per metre."""
    factors = {"m": 1.0, "mm": 1e3, "cm": 1e2, "in": 1 / 0.0254}
    if unit not in factors:
        raise RailContactError(f"unit must be one of {sorted(factors)}, got {unit!r}")
    return factors[unit]


def _parse_float(tok: str, path: Path, lineno: int) -> float:
    try:
        return float(tok)
    except ValueError:
        raise RailContactError(f"{path}:{lineno}: cannot read {tok!r} as a number") from None


def _check_decimal_commas(line: str, raw: str, path: Path, lineno: int) -> None:
    """Raise a :class:`RailContactError` naming the file and line when ``line`` (a data
    line, comments removed) has a comma between two digits while its columns are separated
    by something else (a semicolon, spaces or tabs): a decimal comma, as European
    spreadsheets write ``10,1595`` for 10.1595, which would be split into two numbers."""
    if "," not in line or not re.search(r"\d,\d", line):
        return
    if ";" in line or len(line.split()) >= 2:
        number = re.search(r"[-+]?\d*,\d+", line).group(0)  # type: ignore[union-attr]
        raise RailContactError(
            f"{path}:{lineno}: {raw.strip()!r} has a decimal comma ({number!r}); write "
            f"numbers with a decimal point ({number.replace(',', '.')!r})")


def read_simpack(path: str | Path) -> Profile:
    """Read a SIMPACK ``.prr`` (rail) or ``.prw`` (wheel) profile.

    Applies the file's ``mirror.y``, ``mirror.z``, ``inversion`` and ``units.len.f``
    settings. SIMPACK's z points down: a rail's height is ``-z``; a wheel's z is its radius
    increment. The result is in railcontact's frame (y to the field side, as the
    Manchester benchmark files are written).
    """
    p = Path(path)
    if not p.is_file():
        raise RailContactError(f"profile file not found: {p}")
    settings: dict[str, str] = {}
    pts: list[tuple[float, float]] = []
    in_points = False
    section = ""
    for lineno, raw in enumerate(p.read_text(errors="replace").splitlines(), 1):
        line = raw.split("!")[0].strip()
        if not line:
            continue
        if line.endswith(".begin") and line != "point.begin":
            section = line[: -len(".begin")] + "."
            continue
        if line.endswith(".end") and line != "point.end":
            section = ""
            continue
        if line == "point.begin":
            in_points = True
            continue
        if line == "point.end":
            in_points = False
            continue
        if in_points:
            _check_decimal_commas(line, raw, p, lineno)
            tok = line.replace(",", " ").split()
            if len(tok) < 2:
                raise RailContactError(f"{p}:{lineno}: expected 'y z [weight]', got {raw!r}")
            pts.append((_parse_float(tok[0], p, lineno), _parse_float(tok[1], p, lineno)))
        else:
            m = re.match(r"([\w.]+)\s*=\s*(.+)", line)
            if m:
                settings[section + m.group(1)] = m.group(2).strip().strip("'")
    if not pts:
        raise RailContactError(f"{p}: no profile points found (no point.begin ... point.end)")
    a = np.array(pts)
    ptype = settings.get("header.type")
    kind = "wheel" if ptype == "1" else "rail" if ptype == "0" else (
        "wheel" if p.suffix.lower() == ".prw" else "rail")
    factor = settings.get("spline.units.len.f", "1000")
    try:
        f = float(factor)
    except ValueError:
        f = math.nan
    if not (math.isfinite(f) and f > 0):
        raise RailContactError(f"{p}: spline.units.len.f (the file's length unit per m, 1000 "
                               f"for mm) must be a positive number, got {factor!r}")
    y, z = a[:, 0] / f, a[:, 1] / f
    if settings.get("spline.mirror.y", "0") == "1":
        y = -y
    if settings.get("spline.mirror.z", "0") == "1":
        z = -z
    if kind == "rail":
        z = -z
    if settings.get("spline.inversion", "0") == "1":
        y, z = y[::-1], z[::-1]
    if y.size > 1 and y[0] > y[-1]:
        y, z = y[::-1], z[::-1]
    if kind == "rail":
        y, z = vertical_flanks_cut(y, z)
    return Profile(y, z, kind, p.stem)


def vertical_flanks_cut(y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A rail profile's points (y increasing) without the vertical runs at its ends - the
    vertical sides of an idealised rail head (CONTACT's ``r300_wide``), which a profile
    z(y) cannot hold - but for the top point of each run, where the head's curve meets it.
    The head above is kept as it is; a wheel does not reach below it (a gauge point lower
    than it cannot be placed: :class:`~railcontact.geometry.track.Track` says so)."""
    lo, hi = 0, y.size - 1
    while lo < hi and y[lo + 1] == y[lo] and z[lo + 1] > z[lo]:
        lo += 1
    while hi > lo and y[hi - 1] == y[hi] and z[hi - 1] > z[hi]:
        hi -= 1
    return y[lo:hi + 1], z[lo:hi + 1]


def read_xy(path: str | Path, kind: str, unit: str = "mm") -> Profile:
    """Read a two-column text or CSV profile (y, z) in ``unit`` (comments with # or !).

    The columns are railcontact's frame (module docstring); points may be given in either
    order of y. Columns are separated by spaces, tabs, a comma or a semicolon, and numbers
    written with a decimal point: a line with another number of columns, or with a decimal
    comma (``-70;10,1595``), is an error naming the file and line.
    """
    p = Path(path)
    if not p.is_file():
        raise RailContactError(f"profile file not found: {p}")
    f = _unit_factor(unit)
    rows = []
    for lineno, raw in enumerate(p.read_text(errors="replace").splitlines(), 1):
        line = re.split(r"[#!%]", raw)[0].strip()
        if not line:
            continue
        _check_decimal_commas(line, raw, p, lineno)
        tok = line.replace(",", " ").replace(";", " ").split()
        if len(tok) != 2:
            raise RailContactError(f"{p}:{lineno}: expected two columns 'y z' (separated by "
                                   f"spaces, a comma or a semicolon), got {len(tok)} in "
                                   f"{raw.strip()!r}")
        rows.append((_parse_float(tok[0], p, lineno), _parse_float(tok[1], p, lineno)))
    if not rows:
        raise RailContactError(f"{p}: no profile points found")
    a = np.array(rows) / f
    if a.shape[0] > 1 and a[0, 0] > a[-1, 0]:
        a = a[::-1]
    span = float(np.ptp(a[:, 0]))
    if span < MIN_PROFILE_SPAN:
        big = " (a file in metres read as millimetres)" if unit == "mm" else ""
        raise RailContactError(
            f"profile {p.name!r} spans {span:.3g} m in y with unit {unit!r}{big}; a wheel or "
            f"rail profile spans about 0.1-0.2 m (at least {MIN_PROFILE_SPAN} m): is its "
            "unit right (profile_unit)?")
    return Profile(a[:, 0], a[:, 1], kind, p.stem)


def read_profile(spec: str | Path, kind: str, unit: str = "mm") -> Profile:
    """A profile from a built-in name or a file (``.prr``/``.prw`` SIMPACK, else two columns)."""
    if kind not in KINDS:
        raise RailContactError(f"profile kind must be one of {KINDS}, got {kind!r}")
    s = str(spec)
    key = _ALIASES.get(s.upper(), s.upper())
    if key in _BUILTIN and not Path(s).is_file():
        prof = builtin_profile(key)
        if prof.kind != kind:
            raise RailContactError(f"profile {s!r} is a {prof.kind} profile, not a {kind}")
        return prof
    p = Path(s)
    if not p.is_file():
        raise RailContactError(f"{kind} profile {s!r} is neither a built-in profile "
                               f"({', '.join(sorted(_BUILTIN))}; aliases "
                               f"{', '.join(sorted(_ALIASES))}) nor an existing file")
    if p.suffix.lower() in (".prr", ".prw"):
        prof = read_simpack(p)
        if prof.kind != kind:
            raise RailContactError(f"profile file {p} is a {prof.kind} profile, not a {kind}")
        return prof
    return read_xy(p, kind, unit)
