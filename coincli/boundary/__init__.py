"""Pure estimators of basin-boundary complexity, on label arrays (numpy; scipy imported lazily),
one concept a module (:mod:`.entropy`, :mod:`.fractal_test`, :mod:`.exponent`, :mod:`.wada`).

Every function takes plain arrays (or, for the perturbation method, a classifier callable) and
returns a frozen dataclass; nothing here prints, writes files or knows about the coin model, so the
estimators apply to the basins of any map or flow.

Labels are integer arrays, one outcome class per value (any integers, negative ones included: a
"diverged" or "unsettled" class is an outcome like any other). The optional boolean ``valid`` mask
(same shape) marks the cells whose label is trustworthy; a cell with ``valid=False`` never counts
as evidence. How each estimator excludes such cells, and where it reports how many it excluded, is
said in its docstring.

Estimators
----------
``basin_entropy``
    Basin entropy S_b and boundary basin entropy S_bb of Daza, Wagemakers, Georgeot,
    Guery-Odelin and Sanjuan, "Basin entropy: a new tool to analyze uncertainty in dynamical
    systems", Sci. Rep. 6, 31416 (2016), with the conventions of Attractors.jl's
    ``basin_entropy`` (natural log, non-overlapping boxes, incomplete edge boxes ignored).
``boundary_by_band``
    The same, per band of rows along one axis.
``basins_fractal_test``
    The ball test for fractal boundaries of Puy, Daza, Wagemakers and Sanjuan, "A test for fractal
    boundaries based on the basin entropy", Commun. Nonlinear Sci. Numer. Simul. 95, 105588
    (2021), as Attractors.jl's ``basins_fractal_test``: it also detects fractal boundaries with
    S_bb <= log 2, which the log-2 criterion of ``basin_entropy`` (sufficient only) misses.
``uncertain_fraction`` / ``fit_uncertainty_exponent`` / ``pool_uncertain_fractions``
    The uncertainty exponent alpha by the perturbation method of McDonald, Grebogi, Ott and Yorke,
    "Fractal basin boundaries", Physica D 17, 125 (1985) (and Grebogi, McDonald, Ott and Yorke,
    "Final state sensitivity: an obstruction to predictability", Phys. Lett. A 99, 415 (1983)):
    f(eps) ~ eps**alpha, with f the fraction of points whose outcome changes under a perturbation
    of size eps; the boundary's box-counting dimension is D = dim - alpha.
``uncertainty_exponent_grid``
    alpha from a finished map alone, by box counting as Attractors.jl's
    ``uncertainty_exponent(basins)``.
``wada_merge``
    The merging method of Daza, Wagemakers and Sanjuan, "Ascertaining when a basin is Wada: the
    merging method", Sci. Rep. 8, 9954 (2018), with the conventions of Attractors.jl's
    ``test_wada_merge``.
"""

from .common import LOG2
from .entropy import BandEntropy, BasinEntropy, basin_entropy, boundary_by_band
from .exponent import (
    GridUncertainty,
    UncertainFraction,
    UncertaintyExponent,
    fit_uncertainty_exponent,
    local_exponents,
    pool_uncertain_fractions,
    uncertain_fraction,
    uncertainty_exponent_grid,
)
from .fractal_test import FractalTest, basins_fractal_test, smooth_ball_sbb
from .wada import WadaResult, wada_merge

__all__ = [
    "LOG2",
    "BandEntropy",
    "BasinEntropy",
    "FractalTest",
    "GridUncertainty",
    "UncertainFraction",
    "UncertaintyExponent",
    "WadaResult",
    "basin_entropy",
    "basins_fractal_test",
    "boundary_by_band",
    "fit_uncertainty_exponent",
    "local_exponents",
    "pool_uncertain_fractions",
    "smooth_ball_sbb",
    "uncertain_fraction",
    "uncertainty_exponent_grid",
    "wada_merge",
]
