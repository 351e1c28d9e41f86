"""Size distributions for the parameters an inlet draws per body (a sphere's ``radius``, a
mesh's ``scale``, any scalar parameter of a shape).

Three distributions, each given where a number or a ``(low, high)`` range (uniform) would
go, in Python as an object or in a scene file as a one-key table (the same keys)::

    sim.add_inlet(region, glass, rate=2000, radius=dpm.Normal(1e-3, 1e-4, 8e-4, 1.2e-3))
    radius = { normal = { mean = 1e-3, std = 1e-4, low = 8e-4, high = 1.2e-3 } }
    radius = { lognormal = { median = 1e-3, gsd = 1.3, low = 4e-4, high = 3e-3 } }
    radius = { sieve = { edges = [5e-4, 1e-3, 2e-3], fractions = [0.3, 0.7] } }

- :class:`Normal` (mean, std, truncated to [low, high]) and :class:`LogNormal` (median
  and geometric standard deviation, or mu and sigma of ln(size), truncated to [low, high])
  draw each body independently: they are number distributions, as LIGGGHTS' ``gaussian
  number`` and EDEM's default "number of particles" basis. ``LogNormal(basis="mass")``
  takes median and gsd as the laboratory gives them for a mass (volume) distribution
  (x50,3) and draws the number distribution that has them (Hatch-Choate).
- :class:`Sieve` is a laboratory sieve analysis: class edges and the mass fraction
  retained in each class. The bodies inserted reproduce the *mass* fractions.

Every size is in the units of the parameter it is given to: a radius [m] for ``radius``
(halve sieve apertures, which are diameters), a factor for a mesh's ``scale``. The
truncation range is required: the inlet must know its largest body before the run (its
region check and a stream inlet's slab), and a radius must stay positive. The mass-based
forms (``Sieve``, ``LogNormal(basis="mass")``) need a parameter that scales the whole body
(mass proportional to the size cubed: a sphere's radius, a mesh's scale); an inlet checks
this on its shapes and refuses any other parameter by name.

Draws use the inlet's random generator: an inlet's seed makes them reproducible.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from statistics import NormalDist
from typing import Any

import numpy as np

from .errors import ParameterError
from .parameters import REQUIRED, Parameter, numeric_array, validate

_PHI = NormalDist()
#: the least probability a truncation range may hold of its distribution
MIN_WINDOW = 1e-6
#: how far a sieve table's fractions may sum from 1 (they are then rescaled to sum to 1)
FRACTION_TOLERANCE = 1e-3


class SizeDistribution:
    """A distribution of one scalar shape parameter, truncated to ``[low, high]``.

    Subclasses set ``name`` (the scene file's key), ``parameters``, ``params`` (the
    arguments, plain data: they identify the scene in checkpoints), ``low``, ``high`` and
    ``by_mass`` (True where the mass fractions are what is prescribed), and implement
    :meth:`sample`.
    """

    name = ""
    parameters: dict[str, Parameter] = {}
    by_mass = False
    low = 0.0
    high = 0.0
    params: dict[str, Any] = {}

    def sample(self, rng: np.random.Generator) -> float:
        """One value, drawn with ``rng``."""
        raise NotImplementedError

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and _same(self.params, other.params)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.params.items())
        return f"dpm.{type(self).__name__}({args})"


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return a.keys() == b.keys() and all(
        np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a)


def _phi(x: float) -> float:
    """The standard normal distribution function (accurate in the lower tail)."""
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


def _window(alpha: float, beta: float) -> float:
    """The probability of [alpha, beta] under the standard normal distribution."""
    if alpha > 0.0:  # (the upper tail, mirrored into the lower one)
        alpha, beta = -beta, -alpha
    return _phi(beta) - _phi(alpha)


def _truncated_normal(rng: np.random.Generator, alpha: float, beta: float) -> float:
    """A standard normal value conditioned on [alpha, beta] (inverse distribution
    function; a window in the upper tail is drawn mirrored, where Phi keeps its digits)."""
    flip = alpha > 0.0
    if flip:
        alpha, beta = -beta, -alpha
    pa, pb = _phi(alpha), _phi(beta)
    p = pa + (pb - pa) * float(rng.random())
    p = min(max(p, 1e-300), 1.0 - 1e-16)
    z = min(max(_PHI.inv_cdf(p), alpha), beta)
    return -z if flip else z


def _check(call: str, cls: type[SizeDistribution], given: dict[str, Any]) -> dict[str, Any]:
    return validate(call, cls.parameters, given)


class Normal(SizeDistribution):
    """Normal (Gaussian) distribution of a size: ``mean`` and ``std`` (standard deviation),
    conditioned on ``[low, high]`` (all in the parameter's units, e.g. metres of radius).

    Density ``f(s) = phi((s - mean) / std) / (std (Phi(b) - Phi(a)))`` on [low, high], with
    ``a = (low - mean) / std``, ``b = (high - mean) / std`` (phi, Phi: the standard normal
    density and distribution function); drawn by inverting Phi, so that values are
    redrawn-free and never pile up at the bounds. This is a number distribution: each body
    draws its size independently (as LIGGGHTS' ``radius gaussian number mu sigma``, which
    truncates at mu +- 3 sigma, and EDEM's normal distribution with its caps). The bounds
    are required and explicit because they decide the largest body (a stream inlet's slab,
    the region check) and keep a radius positive; the sample mean and std are those of the
    truncated distribution (they equal ``mean``, ``std`` when the range spans several std).
    A range holding less than 1e-6 of the distribution is refused (a unit mistake).
    """

    name = "normal"
    parameters = {
        "mean": Parameter(doc="mean of the untruncated distribution"),
        "std": Parameter(low=0.0, low_open=True, doc="standard deviation (untruncated)"),
        "low": Parameter(doc="smallest value drawn"),
        "high": Parameter(doc="largest value drawn"),
    }

    def __init__(self, mean: float, std: float, low: float, high: float) -> None:
        call = "dpm.Normal()"
        _check(call, Normal, dict(mean=mean, std=std, low=low, high=high))
        self.params = {"mean": float(mean), "std": float(std), "low": float(low),
                       "high": float(high)}
        self.mean, self.std = float(mean), float(std)
        self.low, self.high = float(low), float(high)
        _ordered(call, self.low, self.high)
        self.alpha = (self.low - self.mean) / self.std
        self.beta = (self.high - self.mean) / self.std
        p = _window(self.alpha, self.beta)
        if not p >= MIN_WINDOW:
            raise ParameterError(
                f"{call}: low={low!r}, high={high!r} hold {p:.3g} of the distribution of "
                f"mean={mean!r}, std={std!r} (at least {MIN_WINDOW:g} allowed): the range "
                "lies far outside it; check the units")

    def sample(self, rng: np.random.Generator) -> float:
        z = _truncated_normal(rng, self.alpha, self.beta)
        return min(max(self.mean + self.std * z, self.low), self.high)


class LogNormal(SizeDistribution):
    """Log-normal distribution of a size, conditioned on ``[low, high]``: ln(size) is
    normal with mean ``mu`` and standard deviation ``sigma``.

    Give either ``median`` and ``gsd`` (the geometric standard deviation, > 1: x50 and
    sigma_g, as a particle-size analysis reports them; mu = ln(median), sigma = ln(gsd),
    the median in the parameter's units) or ``mu`` and ``sigma`` directly (LIGGGHTS'
    ``lognormal mu sigma`` and EDEM's "logarithmic scale", with mu the log of the size in
    the parameter's units, e.g. ln(radius / 1 m)). ``low`` (>= 0) and ``high`` bound the
    sizes drawn (required, as for :class:`Normal`; median and gsd are those of the
    untruncated distribution).

    ``basis="number"`` (default): each body draws ln(size) from the truncated normal
    (number distribution). ``basis="mass"``: median and gsd describe the *mass*
    distribution (a laser-diffraction or sieve x50,3); the mass-weighted density
    f_M(s) ~ s^3 f_N(s) is log-normal with the same sigma when f_N is, so the bodies draw
    ln(size) with mean mu - 3 sigma^2 (Hatch and Choate 1929), truncated to the same range,
    which gives exactly the mass distribution asked for (mass proportional to size^3).
    """

    name = "lognormal"
    parameters = {
        "median": Parameter(default=None, low=0.0, low_open=True,
                            doc="median size (x50) of the untruncated distribution"),
        "gsd": Parameter(default=None, low=1.0, low_open=True,
                         doc="geometric standard deviation (sigma_g > 1)"),
        "mu": Parameter(default=None, doc="mean of ln(size)"),
        "sigma": Parameter(default=None, low=0.0, low_open=True,
                           doc="standard deviation of ln(size)"),
        "low": Parameter(low=0.0, doc="smallest value drawn"),
        "high": Parameter(low=0.0, low_open=True, doc="largest value drawn"),
        "basis": Parameter(default="number", kind="str", doc="number or mass"),
    }

    def __init__(self, median: float | None = None, gsd: float | None = None,
                 low: float | None = None, high: float | None = None, *,
                 mu: float | None = None, sigma: float | None = None,
                 basis: str = "number") -> None:
        call = "dpm.LogNormal()"
        _check(call, LogNormal, dict(median=median, gsd=gsd, mu=mu, sigma=sigma, low=low,
                                     high=high, basis=basis))
        pairs = {"median, gsd": (median, gsd), "mu, sigma": (mu, sigma)}
        given = [k for k, (a, b) in pairs.items() if a is not None or b is not None]
        if len(given) != 1 or None in pairs[given[0]]:
            raise ParameterError(
                f"{call}: give median and gsd (x50 and the geometric standard deviation) or "
                f"mu and sigma (of ln(size)), one pair in full (got median={median!r}, "
                f"gsd={gsd!r}, mu={mu!r}, sigma={sigma!r})")
        if basis not in ("number", "mass"):
            raise ParameterError(f"{call}: basis={basis!r}; allowed: 'number' (each body "
                                 "draws a size) or 'mass' (the mass distribution's median "
                                 "and gsd)")
        if given[0] == "median, gsd":
            self.params = {"median": float(median), "gsd": float(gsd)}  # type: ignore[arg-type]
            self.mu, self.sigma = math.log(float(median)), math.log(float(gsd))  # type: ignore[arg-type]
        else:
            self.params = {"mu": float(mu), "sigma": float(sigma)}  # type: ignore[arg-type]
            self.mu, self.sigma = float(mu), float(sigma)  # type: ignore[arg-type]
        self.params.update(low=float(low), high=float(high), basis=basis)  # type: ignore[arg-type]
        self.low, self.high = float(low), float(high)  # type: ignore[arg-type]
        self.basis = basis
        self.by_mass = basis == "mass"
        _ordered(call, self.low, self.high)
        #: mean of ln(size) of the number distribution drawn
        self.mu_number = self.mu - 3.0 * self.sigma**2 if self.by_mass else self.mu
        self.alpha = ((math.log(self.low) if self.low > 0 else -math.inf)
                      - self.mu_number) / self.sigma
        self.beta = (math.log(self.high) - self.mu_number) / self.sigma
        p = _window(self.alpha, self.beta)
        if not p >= MIN_WINDOW:
            raise ParameterError(
                f"{call}: low={low!r}, high={high!r} hold {p:.3g} of the distribution "
                f"(median {math.exp(self.mu):g}, gsd {math.exp(self.sigma):g}, {basis} "
                f"basis; at least {MIN_WINDOW:g} allowed): the range lies far outside it; "
                "check the units")

    def sample(self, rng: np.random.Generator) -> float:
        z = _truncated_normal(rng, self.alpha, self.beta)
        return min(max(math.exp(self.mu_number + self.sigma * z), self.low), self.high)


class Sieve(SizeDistribution):
    """A sieve analysis: ``edges`` (n + 1 sizes, increasing) bound n classes, and
    ``fractions`` (n values >= 0 summing to 1 within 1e-3) are the mass fractions retained
    in each class (between consecutive sieves), as a laboratory reports a particle-size
    distribution. Sizes are in the parameter's units: for ``radius``, half the sieve
    apertures.

    The bodies inserted reproduce the mass fractions: class i (edges a_i < b_i) is drawn
    with number probability ``p_i = (w_i / M_i) / sum_j (w_j / M_j)`` where w_i is its mass
    fraction and M_i the mean mass of one body of the class (M_i ~ E[s^3 | class i], the
    mass scaling with size^3), so that the expected mass in class i is
    ``p_i M_i / sum_j p_j M_j = w_i``. Within a class the size is drawn ``within =
    "uniform"`` (default: number density uniform in size, E[s^3] = (b^4 - a^4) / (4 (b -
    a))) or ``"log"`` (uniform in log size, density ~ 1/s, E[s^3] = (b^3 - a^3) / (3
    ln(b/a))), for geometric sieve series. The class probabilities are ``number_fractions``.

    Refused, by name: edges not increasing, sizes <= 0, fractions < 0, a number of
    fractions other than edges - 1, fractions summing to other than 1 (percentages: divide
    by 100).
    """

    name = "sieve"
    parameters = {
        "edges": Parameter(kind="any", doc="n + 1 class edges (sieve sizes), increasing"),
        "fractions": Parameter(kind="any", doc="n mass fractions retained per class"),
        "within": Parameter(default="uniform", kind="str", doc="uniform or log"),
    }
    by_mass = True

    def __init__(self, edges: Any, fractions: Any, within: str = "uniform") -> None:
        call = "dpm.Sieve()"
        _check(call, Sieve, dict(edges=edges, fractions=fractions, within=within))
        e, w = numeric_array(edges), numeric_array(fractions)
        if e is None or e.ndim != 1 or len(e) < 2:
            raise ParameterError(f"{call}: edges={edges!r} must be a list of at least two "
                                 "sizes (the sieves bounding the classes)")
        if w is None or w.ndim != 1:
            raise ParameterError(f"{call}: fractions={fractions!r} must be a list of numbers "
                                 "(the mass fraction retained in each class)")
        if len(w) != len(e) - 1:
            raise ParameterError(f"{call}: {len(e)} edges bound {len(e) - 1} classes, but "
                                 f"{len(w)} fractions are given (fractions={fractions!r}); "
                                 "allowed: one fraction per class between consecutive edges")
        if not np.all(np.isfinite(e)) or np.any(e <= 0):
            raise ParameterError(f"{call}: edges={edges!r} must be finite sizes > 0")
        if np.any(np.diff(e) <= 0):
            k = int(np.argmax(np.diff(e) <= 0))
            raise ParameterError(f"{call}: edges={edges!r} are not sorted: edge {k + 1} "
                                 f"({e[k + 1]:g}) is not above edge {k} ({e[k]:g}); allowed: "
                                 "strictly increasing sizes")
        if not np.all(np.isfinite(w)) or np.any(w < 0):
            k = int(np.argmax(~np.isfinite(w) | (w < 0)))
            raise ParameterError(f"{call}: fractions={fractions!r}: fraction {k} is "
                                 f"{w[k]:g}; allowed: mass fractions >= 0")
        total = float(w.sum())
        if not abs(total - 1.0) <= FRACTION_TOLERANCE:
            hint = " (percentages? divide them by 100)" if abs(total - 100) <= 0.1 else ""
            raise ParameterError(f"{call}: fractions={fractions!r} sum to {total:.6g}; "
                                 f"allowed: mass fractions summing to 1 within "
                                 f"{FRACTION_TOLERANCE:g}{hint}")
        if within not in ("uniform", "log"):
            raise ParameterError(f"{call}: within={within!r}; allowed: 'uniform' (sizes "
                                 "uniform within a class) or 'log' (uniform in log size)")
        self.params = {"edges": e.tolist(), "fractions": w.tolist(), "within": within}
        self.edges = e
        self.fractions = w / total
        self.within = within
        a, b = e[:-1], e[1:]
        if within == "uniform":
            cube = (b**4 - a**4) / (4.0 * (b - a))
        else:
            cube = (b**3 - a**3) / (3.0 * np.log(b / a))
        #: E[size^3] within each class
        self.mean_cube = cube
        n = self.fractions / cube
        #: the number fraction of each class (its probability per body drawn)
        self.number_fractions = n / n.sum()
        self._cumulative = np.cumsum(self.number_fractions)
        self._cumulative[-1] = 1.0
        used = np.flatnonzero(self.fractions > 0)
        self.low, self.high = float(a[used[0]]), float(b[used[-1]])

    def sample(self, rng: np.random.Generator) -> float:
        k = int(np.searchsorted(self._cumulative, float(rng.random()), side="right"))
        k = min(k, len(self.fractions) - 1)
        while self.number_fractions[k] == 0.0:  # (round-off at the top: the last class used)
            k -= 1
        a, b, u = float(self.edges[k]), float(self.edges[k + 1]), float(rng.random())
        s = a + (b - a) * u if self.within == "uniform" else a * (b / a) ** u
        return min(max(s, a), b)


def _ordered(call: str, low: float, high: float) -> None:
    if not low < high:
        raise ParameterError(f"{call}: low={low:g} must be below high={high:g}")


#: the distributions by their scene-file name
DISTRIBUTIONS: dict[str, type[SizeDistribution]] = {
    c.name: c for c in (Normal, LogNormal, Sieve)}

FORMS = ", ".join(f"{{ {n} = {{...}} }}" for n in DISTRIBUTIONS)


def is_distribution_table(value: Any) -> bool:
    """A one-key table naming a distribution: ``{"normal": {...}}``."""
    return (isinstance(value, Mapping) and len(value) == 1
            and next(iter(value)) in DISTRIBUTIONS)


def from_table(where: str, value: Mapping) -> SizeDistribution:
    """The distribution a one-key table ``{name: {keyword: value}}`` describes (a scene
    file's inline table, or the same dict in Python)."""
    problems = table_problems(where, value)
    if problems:
        raise ParameterError("\n".join(problems))
    name, kw = next(iter(value.items()))
    cls = DISTRIBUTIONS[name]
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in kw.items()}
    try:
        return cls(**kw)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None


def table_problems(where: str, value: Any) -> list[str]:
    """The problems of form and keys of a distribution table ``{name: {...}}``: an unknown
    name, unknown keys (with the allowed ones), required keys missing (``where`` names the
    parameter, e.g. ``inlets[0]: radius``)."""
    from .scene_file import echo

    if not (isinstance(value, Mapping) and len(value) == 1):
        return [f"{where} = {echo(value)} must be a number, a pair [low, high] or one of "
                f"{FORMS}"]
    name, kw = next(iter(value.items()))
    if name not in DISTRIBUTIONS:
        return [f"{where}: unknown distribution {name} = {echo(kw)}; allowed: "
                f"{', '.join(DISTRIBUTIONS)}"]
    if not isinstance(kw, Mapping):
        return [f"{where}.{name} = {echo(kw)} must be a table of its parameters "
                f"({', '.join(DISTRIBUTIONS[name].parameters)})"]
    import difflib

    spec = DISTRIBUTIONS[name].parameters
    out = []
    for k in kw:
        if k not in spec:
            close = difflib.get_close_matches(str(k), sorted(spec), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            out.append(f"{where}.{name}: unknown key {k} = {echo(kw[k])}{hint}; allowed: "
                       f"{', '.join(sorted(spec))}")
    for k, p in spec.items():
        if p.default is REQUIRED and k not in kw:
            out.append(f"{where}.{name}: {k} is required ({p.doc})")
    return out
