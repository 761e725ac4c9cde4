"""Complete-coverage path planning of the tank-wall climber (seed 001).

One module per step, each testable alone: :mod:`wall` (grid, cell states
eq. 4, seam), :mod:`decompose` (§3.2), :mod:`order` (eq. 5, §3.3),
:mod:`sweep` (eqs. 2–3, §3.4), :mod:`escape` (eqs. 6–9), :mod:`switch`
(§4, eqs. 10–11), :mod:`untwist` and :mod:`relocate` (fewer turns, same
visits), :mod:`lanes` (whole lanes in a searched order), :mod:`prune`
(fewer repeats, no more turns), :mod:`spend` (the cap's unused repeats
bought back as fewer turns) and :mod:`plan`, which joins them; :mod:`measure`
(a plan's figures, Definition 7); :mod:`seam`
plans round the tank, across the wall's seam (the climber's planner);
:mod:`mop_up` routes a robot back to the cells its own record says a sweep missed.
"""

from .measure import CoverageFigures, figures
from .mop_up import mop_up_route
from .plan import CoveragePlan, best_plan, coverage_path, plan_coverage
from .seam import wrap_plan
from .wall import WallSpec, default_wall, load_wall, rasterise

__all__ = [
    "CoverageFigures",
    "CoveragePlan",
    "WallSpec",
    "best_plan",
    "coverage_path",
    "default_wall",
    "figures",
    "load_wall",
    "mop_up_route",
    "plan_coverage",
    "rasterise",
    "wrap_plan",
]
