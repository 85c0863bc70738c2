"""Figures: every function draws on ``ax=None`` (or ``axes=None``) and never uses pyplot state.

* :mod:`~afmforce.plotting.curves`: a measured curve and its analysis (``plot_summary``,
  ``plot_raw``, ``plot_force_separation``, ``plot_residuals``, ``plot_spectrum``);
* :mod:`~afmforce.plotting.maps`: force-map heat maps (``plot_map``, ``write_map_png``);
* :mod:`~afmforce.plotting.indentation`: force vs indentation with the modulus fit (``plot_indentation``);
* :mod:`~afmforce.plotting.trajectory`: a simulated cycle (``plot_trajectory``,
  ``write_trajectory_png``);
* :mod:`~afmforce.plotting.sweep`: a sweep's metric (``plot_metric``);
* :mod:`~afmforce.plotting.calibration`: a thermal spectrum and its fit (``plot_thermal``,
  ``write_thermal_png``).
"""

from __future__ import annotations

from .calibration import plot_thermal, write_thermal_png
from .curves import plot_force_separation, plot_raw, plot_residuals, plot_spectrum, plot_summary
from .indentation import plot_indentation
from .maps import plot_map, write_map_png
from .sweep import plot_metric
from .trajectory import plot_trajectory, write_trajectory_png

__all__ = ["plot_summary", "plot_raw", "plot_force_separation", "plot_residuals", "plot_spectrum",
           "plot_map", "write_map_png", "plot_indentation", "plot_trajectory", "write_trajectory_png", "plot_metric",
           "plot_thermal", "write_thermal_png"]
