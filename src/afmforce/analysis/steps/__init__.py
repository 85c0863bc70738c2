"""The analysis steps, one module per step.

Each module holds one step: its function ``func(state, options) -> state`` and its record, an
:class:`~afmforce.analysis.registry.AnalysisStep` (identifier, requirements, options record,
result fields with their units, how they are read off the step's details). The registry
(:mod:`afmforce.analysis.registry`) imports the modules of :data:`~afmforce.analysis.registry.BUILTIN_MODULES`
and registers their records; the numerical methods the steps call are the modules of
:mod:`afmforce.analysis` (regions, drift, compliance, contact_point, jumps, vdw, fringes, ...).
"""
