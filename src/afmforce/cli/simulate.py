"""``afmforce simulate``: one dynamic approach-retract cycle (paper section 2.3).

Every flag defaults to the paper's Figs 5-6 values, so ``afmforce simulate``
alone runs Fig 5. Values take units (``--velocity 1um/s``, ``--theta0 -15deg``).

Extending the command (e.g. the virtual instrument): append a function
``(parser) -> None`` to :data:`ARGUMENT_GROUPS` that adds an argument group,
the ``dest`` of any output-file flag to :data:`OUTPUT_FLAGS` (so ``--force``
protects it), and a function ``(args, trajectory) -> None`` to
:data:`POST_HOOKS`; hooks run after the trajectory outputs are written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable

from ..errors import ParameterError
from ._validate import (add_field, check_beam, check_outputs, check_simulation_config, check_simulation_options,
                        lazy_help)
from ._outcome import render
from .common import print_json, print_table

__all__ = ["register", "run", "ARGUMENT_GROUPS", "OUTPUT_FLAGS", "POST_HOOKS", "PRE_HOOKS", "config_from_args"]


def _dyn():
    from .. import dynamics

    return dynamics


def _defaults():
    from ..dynamics.config import flat_defaults

    return flat_defaults()


def _q(group, flag, help_, dest=None):
    """A quantity flag (spec: :data:`afmforce._fields.QUANTITIES`: its unit, range and dimension are
    declared there only); the config's default shown in help."""
    name = dest or flag.lstrip("-").replace("-", "_")
    add_field(group, name, flag=flag, help=help_, default_from=lambda: _defaults().get(name))


def _model_group(parser):
    g = parser.add_argument_group("model")
    g.add_argument("--model", choices=("beam", "spring"), default=None,
                   help="beam: inclined cantilever with friction (eqs 22-28); "
                        "spring: mass on a spring (eq 1) (default beam)")
    _q(g, "--quality-factor", "quality factor Q of the lever in its medium "
       "(beam: both free modes, Rayleigh damping; spring: m omega0/Q; none: undamped, the paper)",
       dest="quality_factor")
    _q(g, "--quality-factor-2", "Q of the beam's second free mode "
       "(default: --quality-factor)", dest="quality_factor_2")
    from .calibrate import add_probe_calibration_flag; add_probe_calibration_flag(g, "the quality factor; the spring model also k and the mass giving f0")  # noqa: E501,E702 (issue 34)


def _beam_group(parser):
    g = parser.add_argument_group("inclined cantilever (beam model; Fig 2)")
    _q(g, "--L0", "beam length")
    _q(g, "--L1", "base length")
    _q(g, "--L2", "probe length")
    _q(g, "--theta0", "inclination")
    _q(g, "--k0", "intrinsic spring constant (or give --B)")
    _q(g, "--B", "flexural rigidity")
    _q(g, "--m-joint", "point mass at the beam-base joint", dest="m_joint")
    _q(g, "--m-base", "mass spread along the base", dest="m_base")


def _spring_group(parser):
    g = parser.add_argument_group("simple spring (spring model; eq 1)")
    _q(g, "--spring-constant", "spring constant k", dest="spring_constant")
    _q(g, "--mass", "effective mass m")


def _surface_group(parser):
    g = parser.add_argument_group("surfaces (radius, drainage; eq 2's flags: law van_der_waals below)")
    _q(g, "--radius", "effective radius R")
    _q(g, "--viscosity", "fluid viscosity (drainage)")


def _liquid_group(parser):
    g = parser.add_argument_group("liquid (issue 25; docs/liquid.md; the double layer's flags: law "
                                  "double_layer below)")
    from ..constants import MEDIA
    from ..forces import GEOMETRIES
    g.add_argument("--medium", default=None, choices=sorted(MEDIA),
                   help="set --viscosity and --permittivity of this medium at 25 C "
                        "(flags given explicitly win)")
    lazy_help(g.add_argument("--geometry", default=None, choices=tuple(GEOMETRIES),
                             help="sphere-sphere: the paper (R_eff = R/2); sphere-flat: a colloid probe "
                                  "(R_eff = R) (default "), lambda: f"{_defaults()['geometry']})")
    _q(g, "--slip-length", "slip length b", dest="slip_length")
    _q(g, "--lever-drag", "drag coefficient of the lever body", dest="lever_drag")
    _q(g, "--lever-height", "lever height at contact (0: constant drag)",
       dest="lever_height")


def _laws_groups(parser):
    """One group per surface force law of :mod:`afmforce.surface_laws` (the model's eq 2 and double
    layer included), its flags from the record: the choice of its form (``switch``) and its
    parameters (a parameter shared by two laws, e.g. temperature, appears with the first)."""
    from ..surface_laws import LAWS

    seen: set[str] = set()
    for name, law in LAWS.items():
        g = parser.add_argument_group(f"surface force law {name}: {law.title}",
                                      f"{law.reference}. Valid: {law.validity}.")
        if law.switch is not None:
            sw = law.switch
            g.add_argument("--" + sw.name.replace("_", "-"), dest=sw.name, default=None, choices=tuple(sw.choices),
                           help=f"{sw.help}: " + "; ".join(f"{k}: {v}" for k, v in sw.choices.items())
                                + f" (default {sw.default})")   # the configuration's default: the record's
        for p in law.parameters:
            if p.name not in seen:
                seen.add(p.name)
                add_field(g, p.name, default_from=lambda n=p.name: _defaults().get(n))


def _friction_group(parser):
    g = parser.add_argument_group("tip friction (beam model; eq 28)")
    lazy_help(g.add_argument("--friction", default=None, metavar="LAW", help="friction law: "),
              lambda: "; ".join(f"{k}: {v.formula}" for k, v in _dyn().FRICTION_LAWS.items())
              + f" (default {_defaults()['friction']})")
    _q(g, "--xi", "friction coefficient xi")
    _q(g, "--zeta", "load-dependent coefficient zeta")


def _drive_group(parser):
    g = parser.add_argument_group("drive (substrate position z, up = towards the probe)")
    _q(g, "--velocity", "approach speed")
    _q(g, "--retract-velocity", "retract speed (default: --velocity)",
       dest="retract_velocity")
    _q(g, "--start", "start position (out of contact)")
    _q(g, "--turn", "turn position (limit when turning at a load)")
    _q(g, "--turn-force", "turn when the normal force reaches this",
       dest="turn_force")
    _q(g, "--turn-deflection", "turn when the deflection reaches this",
       dest="turn_deflection")
    _q(g, "--dwell", "pause at the turn")
    _q(g, "--end", "end position of the retract")


def add_sampling_flag(group, default: str | None = None) -> None:
    """``--sampling point|average`` (:data:`afmforce.dynamics.SAMPLING`)."""
    shown = default or "point"
    group.add_argument("--sampling", choices=("point", "average"), default=default,
                       help="what one sample is: the state at the sample time (point) or its mean "
                            f"over the sample interval, as an averaging detector records it "
                            f"(average; removes aliased MHz ringing) (default {shown})")


def _solver_group(parser):
    g = parser.add_argument_group("sampling and solver")
    _q(g, "--sample-rate", "instrument sample rate", dest="sample_rate")
    _q(g, "--rtol", "relative tolerance (velocities, Newton)")
    _q(g, "--atol", "absolute tolerance on positions")
    lazy_help(g.add_argument("--ringing", default=None, metavar="HOW", help="in-contact ringing: "),
              lambda: "; ".join(f"{k}: {v.name}" for k, v in _dyn().RINGING.items())
              + f" (default {_defaults()['ringing']})")
    add_sampling_flag(g)
    _q(g, "--max-steps", "step budget (default: sized from the run, max(2e6, 60 f_max T))",
       dest="max_steps")
    g.add_argument("--check", choices=("off", "auto", "always", "raise"), default="auto",
                   help="convergence guard: re-solve 10x tighter in risky regimes (auto, "
                        "default), always, never (off), or fail instead of warning (raise)")


def _output_group(parser):
    g = parser.add_argument_group("output")
    g.add_argument("--out", metavar="FILE", help="write the trajectory (.csv with units or .h5)")
    g.add_argument("--plot", metavar="FILE.png",
                   help="plot deflection vs separation (apparent and actual) with the static curve")
    g.add_argument("--json", action="store_true", help="print the summary as JSON (SI units)")
    g.add_argument("--force", action="store_true", help="overwrite existing output files")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")


#: Functions ``(parser) -> None`` adding the argument groups, in help order.
ARGUMENT_GROUPS: list[Callable[[argparse.ArgumentParser], None]] = [
    _model_group, _beam_group, _spring_group, _surface_group, _liquid_group, _laws_groups,
    _friction_group,
    _drive_group,
    _solver_group, _output_group,
]
#: ``dest`` names of output-file flags that --force protects.
OUTPUT_FLAGS: list[str] = ["out", "plot"]
#: Functions ``(args, trajectory) -> None`` run after the outputs are written.
POST_HOOKS: list[Callable[[argparse.Namespace, object], None]] = []
#: Checks of the hooks' own inputs, run before the simulation: ``hook(args)`` raises to refuse.
PRE_HOOKS: list[Callable[[argparse.Namespace], None]] = []


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``simulate`` sub-command."""
    p = subparsers.add_parser(
        "simulate", help="simulate a dynamic approach-retract cycle (spring or inclined beam)",
        description="Simulate one approach-(dwell-)retract cycle with the compiled stiff "
                    "integrator. Defaults: the paper's Fig 5 (beam, xi = 0.1 kg/s, 0.1 um/s, "
                    "start -40 nm, turn +20 nm, end -230 nm).")
    for add in ARGUMENT_GROUPS:
        add(p)
    p.set_defaults(func=run)
    return p


def config_from_args(args: argparse.Namespace):
    """The :class:`~afmforce.dynamics.SimulationConfig` given by the flags."""
    from ..dynamics import SimulationConfig
    from ..dynamics.config import FLAT

    from .calibrate import calibrated_probe; calibrated_probe(args)  # noqa: E702 (issue 34: --probe-calibration)
    overrides = {k: v for k, v in vars(args).items() if k in FLAT and v is not None}
    if getattr(args, "medium", None):
        from ..constants import MEDIA
        overrides = {**MEDIA[args.medium], **overrides}
    check_simulation_options(args, overrides)  # ranges were checked while parsing
    if overrides.get("model", "beam") == "beam":     # the record checks it too, naming fields, not flags
        from ..dynamics.config import flat_defaults

        probe = {**flat_defaults(), **overrides}
        check_beam(probe["L0"], probe["L1"], probe["L2"], k0=overrides.get("k0"),
                   B=overrides.get("B", None if "k0" in overrides else probe["B"]))
    cfg = SimulationConfig(**overrides)
    check_simulation_config(cfg)
    return cfg


def _progress_bar(args):
    if args.no_progress or args.json or not sys.stderr.isatty():
        return None, None
    from .common import progress_bar

    return progress_bar("simulate", unit="s", leave=False)


def run(args: argparse.Namespace) -> int:
    """Run the command; returns the exit status."""
    import warnings

    from ..dynamics import DynamicsWarning, simulate
    from ..dynamics.guard import ConvergenceWarning

    check_outputs([("--" + dest.replace("_", "-"), getattr(args, dest, None)) for dest in OUTPUT_FLAGS],
                  force=args.force, inputs=[getattr(args, "probe_calibration", None)])
    if args.out and Path(args.out).suffix.lower() not in (".csv", ".h5", ".hdf5"):
        raise ParameterError(f"cannot write {args.out}: --out takes a .csv or .h5 file")
    if args.plot and Path(args.plot).suffix.lower() != ".png":
        raise ParameterError(f"cannot write {args.plot}: --plot takes a .png file")
    cfg = config_from_args(args)
    for hook in PRE_HOOKS:   # their inputs checked before the simulation (and before any compile)
        hook(args)
    bar, update = _progress_bar(args)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", DynamicsWarning)
        warnings.simplefilter("always", ConvergenceWarning)
        try:
            traj = simulate(cfg, progress=update, check=getattr(args, "check", "auto"))
        finally:
            if bar is not None:
                bar.close()
    for w in caught:
        print(f"warning: {render(str(w.message))}", file=sys.stderr)   # `quality_factor` -> --quality-factor
    if args.out:
        traj.write(args.out, force=args.force)
    if args.plot:
        plot_trajectory(traj, args.plot, force=args.force)
    for hook in POST_HOOKS:
        hook(args, traj)
    if args.json:
        print_json(traj.summary())
    else:
        _print_summary(traj)
    return 0


def _print_summary(traj) -> None:
    e, s = traj.events, traj.solver
    rows = [
        ("model", traj.config.model, ""),
        ("spring constant k", f"{traj.spring_constant:.5g} N/m", ""),
        ("calibration factor (eq 15)", _per_rad(traj.calibration_factor, traj), ""),
        ("jump-in", e.jump_in_note, ""),
        ("jump-in position z", e.jump_in_position, "m"),
        ("jump-in separation h", e.jump_in_separation, "m"),
        ("contact position z", e.contact_position, "m"),
        ("min deflection before contact", e.min_deflection, "m"),
        ("min apparent deflection before contact", e.min_apparent_deflection, "m"),
        ("apparent-deflection spike", e.spike_height, "m"),
        ("compliance offset z_in - z_out", e.hysteresis_offset, "m"),
        ("simulated calibration slope", _per_rad(e.compliance_slope, traj), ""),
        *_pull_off_rows(traj),
        ("solver", f"{s.status}: {s.steps} steps ({s.rejected} rejected), "
                   f"{s.rhs_evaluations} f-evals, {s.wall_time:.3g} s", ""),
        ("convergence check", s.check, ""),
    ]
    print_table(rows, title="afmforce simulate")


def _per_rad(value: float, traj) -> str:
    """A calibration factor [m/rad] in nm/rad; the spring model's lever has no angle (eq 15 is the
    inclined beam's), and a run that never reached contact has no compliance line: said, not NaN."""
    import math

    if traj.config.model == "spring":
        return "- (the spring model has no lever angle: eq 15 is the inclined beam's)"
    return f"{value * 1e9:.5g} nm/rad" if math.isfinite(value) else "-"


def _pull_off_rows(traj) -> list[tuple]:
    """The pull-off rows. A retract that ends in contact has no pull-off: the most negative force
    on it (``events.pull_off_force``, the lever's pull at the end of the travel or a bounce) is
    then a bound on the adhesion, not shown as a pull-off force beside a NaN position."""
    import math

    e = traj.events
    if math.isfinite(e.contact_time) and not math.isfinite(e.pull_off_position):
        end = float(traj.piezo_position[-1]) * 1e9
        return [("pull-off", f"none: still in contact at the end of the retract (z = {end:.4g} nm); "
                             "retract further (end)", ""),
                ("most negative force in contact", e.pull_off_force, "N")]
    return [("pull-off position z", e.pull_off_position, "m"), ("pull-off force", e.pull_off_force, "N")]


def plot_trajectory(traj, path, force: bool = False):
    """Deflection vs separation (actual and apparent) with the static curve, as a PNG."""
    from ..plotting import write_trajectory_png

    return write_trajectory_png(traj, path, force=force)


# Virtual instrument (issue 4; afmforce.cli._instrument_opts): --instrument, --seed, --raw, ...
from ._instrument_opts import add_instrument_arguments, check_instrument_args, record_from_args  # noqa: E402

ARGUMENT_GROUPS.append(add_instrument_arguments)
OUTPUT_FLAGS.append("raw")
PRE_HOOKS.append(check_instrument_args)
POST_HOOKS.append(record_from_args)
