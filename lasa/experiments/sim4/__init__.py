"""Fig. sim4: goals never seen in training, through the context map h (Secs. IV-C, V-D), notebook 07.

:mod:`.episodes` runs the users, :mod:`.analysis` fits and judges (lines through the origin, as the
paper's; readings ``@joint_space``, ``@intercept``, ``@ee_line``), :mod:`.figure` draws."""

from lasa.experiments.sim4.analysis import boot_values, claims
from lasa.experiments.sim4.episodes import COLUMNS, NAME, Config, run
from lasa.experiments.sim4.figure import plot

__all__ = ["NAME", "COLUMNS", "Config", "run", "claims", "boot_values", "plot"]
