"""Command-line flags derived from field metadata, and the checks made before any work.

- :func:`add_field` adds ``--flag VALUE`` for a quantity of
  :data:`afmforce._fields.QUANTITIES` (or any :class:`~afmforce._fields.FieldSpec`):
  the value takes units, is checked against the valid range while parsing
  (exit 2, one line), and the help shows the range and the default in the
  user's units. A default that only a heavy module knows (``SimulationConfig``)
  is given as ``default_from=callable`` and computed when help is printed,
  never when the parser is built.
- :func:`check_output` fails before the work if an output cannot be written.
- :func:`refuse_ignored` refuses options that the chosen model ignores.
- :func:`confirm_size` refuses very large runs without ``--yes``.

Nothing here imports numpy, numba, dask or matplotlib.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterable

from .._fields import QUANTITIES, FieldSpec
from ..limits import CONFIRM_RUNS, MAX_SAMPLES, check_samples, simulation_samples  # noqa: F401  (re-export)
from ..errors import OutputExistsError, ParameterError, UnitError

__all__ = ["HelpFormatter", "add_field", "add_choice", "field_type", "check_output", "check_outputs", "check_folder_outputs", "refuse_ignored", "confirm_size",
           "lazy_help", "given", "quantity_list", "check_common", "refuse_empty_values", "COUNTS"]


class HelpFormatter(argparse.HelpFormatter):
    """Help formatter that appends lazily computed text (defaults, choices) at print time."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        extra = getattr(action, "lazy_help", None)
        return text if extra is None else text + extra().replace("%", "%%")


def lazy_help(action: argparse.Action, text: Callable[[], str]) -> argparse.Action:
    """Append ``text()`` to ``action``'s help when the help is printed."""
    action.lazy_help = text
    return action


def field_type(spec: FieldSpec, name: str, flag: str) -> Callable[[str], Any]:
    """An argparse ``type=``: value with units -> SI, checked against ``spec``'s range."""

    def convert(text: str):
        from ..units import parse_typed

        try:
            value = parse_typed(text, spec.dimension, flag)
            return spec.check(value, name, flag, typed=text)
        except (ParameterError, UnitError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = spec.dimension  # argparse names it in some messages
    convert.spec = spec
    return convert


def add_field(group, name: str, *, flag: str | None = None, dest: str | None = None,
              default: Any = None, default_from: Callable[[], Any] | None = None,
              help: str | None = None, spec: FieldSpec | None = None, **kw) -> argparse.Action:
    """Add ``--flag VALUE`` for quantity ``name`` (a key of :data:`QUANTITIES`, or give ``spec``).

    Parameters
    ----------
    flag : str
        Default ``--<name>`` with ``_`` -> ``-``.
    dest : str
        Namespace attribute; default ``name``.
    default : any
        Parsed default [SI], shown in the help in the field's display unit.
    default_from : callable
        Returns the default to *show* (the value itself stays ``default``),
        called only when the help is printed.
    help : str
        Help text; default the spec's.
    """
    spec = spec or QUANTITIES[name]
    flag = flag or "--" + name.replace("_", "-")
    text = help or spec.help
    text += f" [{spec.unit}]" if spec.unit and f"[{spec.unit}]" not in text else ""

    def tail() -> str:
        parts = []
        if spec.bounded:
            parts.append(f"range {spec.range_text()}")
        shown = default if default_from is None else default_from()
        if shown is not None:
            parts.append(f"default {spec.show(shown)}")
        return f" ({'; '.join(parts)})" if parts else ""

    action = group.add_argument(flag, dest=dest or name, type=field_type(spec, dest or name, flag),
                                default=default, metavar="VALUE", help=text, **kw)
    return lazy_help(action, tail)


def add_choice(group, name: str, *, flag: str | None = None) -> argparse.Action:
    """Add ``--flag WORD`` for the setting ``name`` of :data:`afmforce._fields.ANALYSIS_CHOICES`: its
    choices, default and help as declared there (the web's field reads the same declaration)."""
    from .._fields import ANALYSIS_CHOICES

    spec = ANALYSIS_CHOICES[name]
    return group.add_argument(flag or "--" + name.replace("_", "-"), dest=name, choices=spec.choices,
                              default=spec.default, help=f"{spec.help} (default {spec.default})")


def given(args: argparse.Namespace, dest: str) -> bool:
    """Whether option ``dest`` has a value (was given, or has a non-None default)."""
    return getattr(args, dest, None) is not None


def refuse_ignored(args: argparse.Namespace, rules: Iterable[tuple[str, str, bool, str]]) -> None:
    """Refuse options that the chosen model ignores.

    ``rules``: ``(dest, flag, applies, why)``; an option with a value whose
    ``applies`` is false raises ``ParameterError("{flag} is ignored {why}")``.
    """
    for dest, flag, applies, why in rules:
        if not applies and given(args, dest):
            raise ParameterError(f"{flag} is ignored {why}; drop it")


def _nearest_existing(path: Path) -> Path:
    p = path
    while not p.exists():
        if p.parent == p:
            break
        p = p.parent
    return p


def _can_create_in(folder: Path) -> bool:
    """Really try: create and remove a temporary file (os.access lies for root and read-only mounts)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".afmforce-write-test-", dir=folder)
    except OSError:
        return False
    os.close(fd)
    os.unlink(tmp)
    return True


def check_output(path, *, flag: str = "--out", force: bool = True, folder: bool = False) -> Path:
    """Fail before any work if ``path`` cannot be written (exit 2 via the error).

    Parameters
    ----------
    folder : bool
        ``path`` is an output folder (created if missing) rather than a file.
    force : bool
        For a file: overwriting an existing one is allowed.

    Raises
    ------
    OutputExistsError
        A file exists and ``force`` is false.
    ParameterError
        The path, or the folder it would be created in, cannot be written.
    """
    path = Path(path)
    if folder:
        if path.exists() and not path.is_dir():
            raise ParameterError(f"{flag} {path} exists and is not a folder")
    elif path.is_dir():
        raise ParameterError(f"{flag} {path} is a folder; give a file name")
    elif path.exists() and not force:
        raise OutputExistsError(f"{path} exists; choose another name or pass --force to overwrite")
    base = path if folder and path.is_dir() else _nearest_existing(path.parent if not folder else path)
    if not base.is_dir():
        raise ParameterError(f"{flag} {path} cannot be written: {base} is not a folder")
    if not _can_create_in(base):
        raise ParameterError(f"{flag} {path} cannot be written: no permission to write in {base}")
    return path


def check_outputs(outputs: Iterable[tuple[str, Any]], *, force: bool, inputs: Iterable[Any] = ()) -> list[Path]:
    """Every output file of one command, checked before any work.

    ``outputs``: ``(flag, path)`` pairs (a ``None`` path is skipped). Each must be
    writable (:func:`check_output`), an existing file is refused without ``force``,
    no two flags may name the same file (the second would replace the first), and none
    may be one of the command's ``inputs`` (files it reads; ``None`` skipped), even with
    ``force``: an input file is never modified.

    Raises
    ------
    OutputExistsError, ParameterError
    """
    from .._files import check_writable

    seen: dict[str, str] = {}
    read = {os.path.normcase(os.path.realpath(p)) for p in inputs if p and Path(p).is_file()}
    out = []
    for flag, path in outputs:
        if not path:
            continue
        if os.path.normcase(os.path.realpath(path)) in read:
            raise ParameterError(f"{flag} {path} is a file this command reads; give the output another name "
                                 "(input files are never modified)")
        check_writable(path, force)
        p = check_output(path, flag=flag, force=force)
        key = os.path.normcase(os.path.realpath(p))
        if key in seen:
            raise ParameterError(f"{seen[key]} and {flag} name the same file {path}; give each output its own name")
        seen[key] = flag
        out.append(p)
    return out


def check_folder_outputs(folder, names: Iterable[str], *, flag: str, force: bool) -> None:
    """Refuse, without ``force``, to write into ``folder`` files that exist already (written by an
    earlier run, not this one): ``names`` are glob patterns of what the command writes there."""
    folder = Path(folder)
    check_output(folder, flag=flag, folder=True)
    if force or not folder.is_dir():
        return
    existing = sorted({p for pattern in names for p in folder.glob(pattern) if p.is_file()})
    if existing:
        raise OutputExistsError(
            f"{flag} {folder} holds {len(existing)} file(s) this command would replace (e.g. {existing[0].name}); "
            "choose another folder or pass --force to overwrite")


def confirm_size(n: int, limit: int, *, yes: bool, what: str, unit: str = "runs") -> None:
    """Refuse ``n`` > ``limit`` units of work unless ``yes``."""
    if n > limit and not yes:
        raise ParameterError(f"{what}: {n:,} {unit} is more than {limit:,}; check the numbers, "
                             "then pass --yes to run them")


def check_beam(L0: float, L1: float, L2: float, *, k0: float | None = None, B: float | None = None,
               prefix: str = "--") -> None:
    """:func:`afmforce._fields.check_beam` with the names written as flags (``prefix``)."""
    from .._fields import check_beam as check

    check(L0, L1, L2, k0=k0, B=B, prefix=prefix)


def _flag(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def check_simulation_options(args: argparse.Namespace, overrides: dict) -> None:
    """Refuse options the chosen model ignores (``simulate``; see :func:`refuse_ignored`).

    Beam-only flags with ``--model spring`` and spring-only flags with the
    beam; friction coefficients the friction law does not use; virtual-AFM
    options without ``--raw`` (the recorded curve would go nowhere).
    """
    from ..dynamics import FRICTION_LAWS
    from ..dynamics.config import FLAT

    check_choices(overrides, "--")
    model = overrides.get("model", "beam")
    by_model = f"by --model {model}" + ("" if "model" in overrides else " (the default)")
    # the other model's probe fields; friction acts on the beam only (the spring has no lateral motion)
    rules = [(d, _flag(d), model in w.models and (w.part != "friction" or model == "beam"), by_model)
             for d, w in FLAT.items() if w.part in ("probe", "friction") and w.field is not None]
    law = FRICTION_LAWS[overrides.get("friction", "viscous")]
    if model == "beam":
        by_law = f"by --friction {law.key}" + ("" if "friction" in overrides else " (the default)")
        rules += [(d, _flag(d), d in law.parameters, by_law) for d in ("xi", "zeta")]
    refuse_ignored(args, rules)
    if not getattr(args, "raw", None):
        used = [d for d in vars(args) if d.startswith("instrument_param__") or d in ("instrument", "instrument_config")]
        used += ["seed"] if "raw" in vars(args) else []
        for dest in used:
            if given(args, dest):
                flag = ("--" + dest.split("__", 1)[1].replace("__", "-").replace("_", "-")
                        if dest.startswith("instrument_param__") else _flag(dest))
                raise ParameterError(f"{flag} is ignored without a virtual-instrument output: add --raw FILE "
                                     "(and --instrument ideal|typical|paper|liquid), or drop it")


def check_simulation_config(cfg) -> None:
    """Checks of a built :class:`~afmforce.dynamics.SimulationConfig` before it is run:
    the beam is a cantilever (:func:`check_beam`) and the sample count is sane."""
    if cfg.model == "beam":
        p = cfg.probe
        check_beam(p.L0, p.L1, p.L2, k0=p.k0, B=p.B)
    d = cfg.drive
    check_samples(simulation_samples(d.start, d.turn, d.end, d.velocity, d.retract_velocity,
                                     d.dwell, cfg.solver.sample_rate))
    cfg.validate()      # the start is out of contact (a static solve)


def _registries() -> dict[str, dict]:
    from ..dynamics import FRICTION_LAWS, MODELS, RINGING, SAMPLING

    return {"model": MODELS, "friction": FRICTION_LAWS, "ringing": RINGING, "sampling": SAMPLING}


def check_choices(values: dict, prefix: str = "--") -> None:
    """Refuse unknown names of the simulation's registries (model, friction, ringing)."""
    for name, registry in _registries().items():
        if name in values and values[name] not in registry:
            raise ParameterError(f"{prefix}{name} {values[name]}: unknown; choose one of {', '.join(registry)}")



_SAMPLE_WORST = {"start": min, "turn": max, "end": min, "velocity": min, "retract_velocity": min,
                 "dwell": max, "sample_rate": max}


def check_sweep_models(values: dict[str, list]) -> None:
    """Refuse a probe field that some of the sweep's models do not have (``--set k0=...`` with
    ``--grid model=spring,beam``): every such run would fail."""
    from ..dynamics.config import FLAT

    models = {v for v, _ in values.get("model", [])} or {"beam"}
    for name, entries in values.items():
        where = FLAT.get(name)
        lacking = sorted(models - set(where.models)) if where is not None else []
        if lacking and name != "model":
            raise ParameterError(
                f"{entries[0][1]}: {name} is a field of the {where.models[0]} model's probe, and this "
                f"sweep's runs with model {', '.join(lacking)} have none; sweep the models separately")


def check_simulation_sweep(spec, *, yes: bool) -> None:
    """Checks of a simulation sweep before anything is dispatched.

    The number of runs (more than :data:`CONFIRM_RUNS` needs ``yes``), every
    value of every grid axis, range bound and ``--set`` against the field's
    valid range and the registries, and the sample count of the most
    demanding combination (slowest speeds, longest drive, highest rate).
    """
    from .._fields import check as check_value
    from ..dynamics.config import flat_defaults

    confirm_size(spec.n_runs, CONFIRM_RUNS, yes=yes, what="this sweep")
    values: dict[str, list] = {}
    origins = getattr(spec, "origins", {})   # a settings file's entries: named as written there (file, table, key)

    def where(flag: str, name: str) -> str:
        return origins.get(name) or f"{flag} {name}"

    for axis in spec.grid:
        values.setdefault(axis.name, []).extend((v, where("--grid", axis.name)) for v in axis.values)
    for r in spec.ranges:
        if not r.lo < r.hi:
            raise ParameterError(f"{where('--range', r.name)}={r.lo:g}:{r.hi:g} [SI]: the low end must lie below "
                                 "the high end (NAME=LO:HI)")
        values.setdefault(r.name, []).extend(((r.lo, where("--range", r.name)), (r.hi, where("--range", r.name))))
    for name, value in spec.fixed:
        values.setdefault(name, []).append((value, where("--set", name)))
    for name, entries in values.items():
        for value, where in entries:
            if name in _registries():
                check_choices({name: value}, prefix=where[: -len(name)])
            else:
                check_value(name, value, where)
    check_sweep_models(values)
    defaults = flat_defaults()
    worst = {}
    for name, pick in _SAMPLE_WORST.items():
        candidates = [v for v, _ in values.get(name, []) if v is not None] or [defaults[name]]
        worst[name] = pick(candidates) if None not in candidates else None
    n = simulation_samples(**worst)
    if n > MAX_SAMPLES:
        check_samples(n, where="the most demanding run of this sweep: ")
    from ..sweep.simulation import check_runs
    check_runs(spec)


#: Integer options of any command (dest -> smallest valid value), checked by :func:`check_common`.
COUNTS = {"workers": 1, "chunk_size": 1, "starts": 1, "curves": 2, "n": 1, "seed": 0}
#: Integer options with a cap of :mod:`afmforce.limits` (dest -> (name of the cap there, what is counted)).
CAPPED_COUNTS = {"starts": ("MAX_STARTS", "local fits")}


def check_common(args: argparse.Namespace) -> None:
    """Checks made for every command before it runs: the counts of :data:`COUNTS`, a Dask
    scheduler's address."""
    for dest, lo in COUNTS.items():
        value = getattr(args, dest, None)
        if isinstance(value, int) and not isinstance(value, bool) and value < lo:
            raise ParameterError(f"{_flag(dest)} must be at least {lo}, got {value}")
    for dest, (cap, what) in CAPPED_COUNTS.items():
        value = getattr(args, dest, None)
        if isinstance(value, int) and not isinstance(value, bool):
            from .. import limits

            limits.check_count(_flag(dest), value, getattr(limits, cap), what)
    if isinstance(getattr(args, "workers", None), int):
        from ..sweep.executors import check_workers

        check_workers(args.workers)
    if getattr(args, "scheduler", None) is not None:
        from ..sweep.executors import check_scheduler

        check_scheduler(args.scheduler)


def refuse_empty_values(parser: argparse.ArgumentParser, argv: list[str]) -> None:
    """Refuse an option given an empty value (``--out ''``, ``--only=``): it would mean "here" or
    "the default" silently. ``parser`` is the command's parser (it knows which options take values)."""
    actions = parser._option_string_actions
    for i, tok in enumerate(argv):
        if not tok.startswith("--"):
            continue
        flag, eq, value = tok.partition("=")
        action = actions.get(flag)
        if action is None or action.nargs == 0:
            continue
        if eq and not value.strip() or not eq and i + 1 < len(argv) and not argv[i + 1].strip():
            raise ParameterError(f"{flag}: empty value; give one (afmforce {parser.prog.split()[-1]} --help)")
    if any(not tok.strip() for tok in argv):  # afmforce analyze '' would mean the current folder
        raise ParameterError("an empty argument (''); give a file, a folder or a value")


def quantity_list(name: str, flag: str, dimension: str | None = None) -> Callable[[str], tuple]:
    """An argparse ``type=`` for ``V1,V2,...`` with units: each value checked against the range of
    quantity ``name`` of :data:`QUANTITIES` (the same range as the single-value flag of every
    command); an empty list is refused."""
    spec = QUANTITIES[name]

    def convert(text: str) -> tuple:
        from ..units import parse_typed

        parts = [t.strip() for t in text.split(",")]
        if not any(parts):
            raise argparse.ArgumentTypeError(f"{flag}: empty list; give one or more comma-separated values "
                                             f"with units [{spec.unit}]")
        if not all(parts):
            raise argparse.ArgumentTypeError(f"{flag} {text}: an empty value between commas")
        try:
            return tuple(spec.check(parse_typed(t, dimension or spec.dimension, flag), name, flag, typed=t)
                         for t in parts)
        except (ParameterError, UnitError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = f"comma-separated {spec.dimension}s"
    return convert
