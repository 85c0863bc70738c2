"""Instrument configuration: parameter table, TOML files and overrides.

Every component parameter is listed in :data:`PARAMETERS` (built from the
dataclass fields and their metadata: dimension, unit, help), which drives
TOML parsing, the command-line flags ``--<component>-<parameter>`` and the
docs table. A TOML file names a preset and overrides parameters by
component; values are SI numbers or strings with units::

    preset = "paper"            # optional; the --instrument flag wins
    seed = 7                    # optional; the --seed flag wins

    [piezo]
    hysteresis = 0.1
    creep_times = ["0.1 s", "1 s"]

    [photodiode]
    sensitivity = "25 nm/V"
    saturation = "none"         # switch an optional parameter off

The same tables may sit under an ``[instrument]`` table of a larger file.
"""

from __future__ import annotations

import dataclasses
import os
import tomllib
from dataclasses import dataclass
from typing import Any, Mapping

from .._files import read_settings
from ..errors import FileFormatError, ParameterError
from ..units import DIMENSIONS, parse_value
from .instrument import COMPONENTS, Instrument
from .presets import get_preset

__all__ = ["Parameter", "PARAMETERS", "parse_parameter", "parse_config", "load_config", "build_instrument",
           "parameters_markdown"]

_NONE_WORDS = {"none", "off", "null", ""}


@dataclass(frozen=True)
class Parameter:
    """One configurable instrument parameter.

    Attributes
    ----------
    component, name : str
        Component (``piezo`` ...) and field name.
    dimension : str
        For unit parsing (see :data:`afmforce.units.DIMENSIONS`; also
        ``integer`` and ``voltage_rate``).
    unit : str
        SI unit.
    help : str
        One-line description.
    is_list, optional : bool
        A tuple of values; may be ``None`` (unset).
    """

    component: str
    name: str
    dimension: str
    unit: str
    help: str
    is_list: bool
    optional: bool

    @property
    def key(self) -> str:
        """``component.name``."""
        return f"{self.component}.{self.name}"

    @property
    def flag(self) -> str:
        """Command-line flag ``--component-name``."""
        return f"--{self.component}-{self.name.replace('_', '-')}"


def _table() -> dict[str, Parameter]:
    out: dict[str, Parameter] = {}
    for comp, cls in COMPONENTS.items():
        for f in dataclasses.fields(cls):
            typ = str(f.type)
            p = Parameter(comp, f.name, f.metadata["dimension"], f.metadata["unit"], f.metadata["help"],
                          is_list="tuple" in typ, optional="None" in typ)
            out[p.key] = p
    return out


#: ``"component.name"`` -> :class:`Parameter`, for every component parameter.
PARAMETERS: dict[str, Parameter] = _table()


def _scalar(value: Any, p: Parameter, where: str):
    if isinstance(value, bool):
        raise ParameterError(f"{where} expects a number, got {value!r}")
    if p.dimension == "integer":
        return parse_value(value, "integer", where)
    if isinstance(value, (int, float)):
        return float(value)
    if not isinstance(value, str):
        raise ParameterError(f"{where} expects a number or a value with units, got {value!r}")
    if p.dimension in DIMENSIONS:
        return parse_value(value, p.dimension, where)
    raise ParameterError(f"{where}: unknown dimension {p.dimension!r}")  # pragma: no cover


def parse_parameter(key: str, value: Any, where: str | None = None):
    """Convert a TOML or command-line value of ``component.name`` to its SI value.

    Lists accept TOML arrays or comma-separated strings; optional parameters
    accept ``"none"``/``"off"``.

    Raises
    ------
    ParameterError
        Unknown parameter or a value of the wrong kind/dimension.
    """
    if key not in PARAMETERS:
        comp = key.split(".")[0]
        valid = [k for k in PARAMETERS if k.startswith(comp + ".")] or list(PARAMETERS)
        raise ParameterError(f"unknown instrument parameter {key!r}; valid: {', '.join(valid)}")
    p = PARAMETERS[key]
    where = where or key
    if p.optional and (value is None or (isinstance(value, str) and value.strip().lower() in _NONE_WORDS)):
        return None
    if p.is_list:
        if isinstance(value, str):
            items = [v.strip() for v in value.split(",") if v.strip()]
        elif isinstance(value, (list, tuple)):
            items = list(value)
        else:
            items = [value]
        return tuple(_scalar(v, p, where) for v in items)
    return _scalar(value, p, where)


def load_config(path: str | os.PathLike) -> dict[str, Any]:
    """Read an instrument TOML file into ``{"preset", "seed", "parameters": {key: SI value}}``.

    Raises
    ------
    FileFormatError
        Unreadable file or invalid TOML.
    ParameterError
        Unknown tables or parameters, bad values.
    """
    try:
        data = tomllib.loads(read_settings(path, "an instrument TOML file"))
    except IsADirectoryError:
        raise FileFormatError(f"instrument config {path} is a folder; give a .toml file") from None
    except OSError as exc:
        raise FileFormatError(f"cannot read instrument config {path}: {exc.strerror or exc}") from exc
    except UnicodeDecodeError:
        raise FileFormatError(f"instrument config {path} is not a UTF-8 text file (TOML expected)") from None
    except tomllib.TOMLDecodeError as exc:
        raise FileFormatError(f"{path} is not valid TOML: {exc}") from exc
    return parse_config(data, source=str(path))


def parse_config(data: Mapping[str, Any], source: str = "config") -> dict[str, Any]:
    """Validate a configuration mapping (see :func:`load_config`)."""
    if isinstance(data.get("instrument"), Mapping):
        data = data["instrument"]
    preset = data.get("preset")
    if preset is not None and not isinstance(preset, str):
        raise ParameterError(f"{source}: preset must be a name such as \"paper\", got {preset!r}")
    seed = data.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise ParameterError(f"{source}: seed must be a whole number >= 0, got {seed!r}")
    params: dict[str, Any] = {}
    for table, values in data.items():
        if table in ("preset", "seed"):
            continue
        if table not in COMPONENTS or not isinstance(values, Mapping):
            raise ParameterError(f"{source}: unknown entry {table!r}; expected preset = \"...\", seed = N and tables "
                                 f"{', '.join('[' + c + ']' for c in COMPONENTS)}")
        for name, value in values.items():
            key = f"{table}.{name}"
            params[key] = parse_parameter(key, value, f"{source}: {key}")
    return {"preset": preset, "seed": seed, "parameters": params}


def build_instrument(preset: str | None = None, config: Mapping[str, Any] | None = None,
                     overrides: Mapping[str, Any] | None = None) -> Instrument:
    """An instrument from a preset, a parsed config and parameter overrides.

    Parameters
    ----------
    preset : str or None
        Preset name; wins over the config's. Default ``"ideal"``.
    config : mapping or None
        Output of :func:`load_config` / :func:`parse_config`.
    overrides : mapping or None
        ``{"component.name": value}``; values are parsed like TOML values and
        applied after the config's.

    Returns
    -------
    Instrument
        Named after the preset, with ``"+custom"`` when parameters were changed.
    """
    config = config or {}
    name = preset or config.get("preset") or "ideal"
    base = get_preset(name)
    changes: dict[str, Any] = dict(config.get("parameters", {}))
    for key, value in (overrides or {}).items():
        changes[key] = parse_parameter(key, value)
    if not changes:
        return base
    by_component: dict[str, dict[str, Any]] = {}
    for key, value in changes.items():
        comp, field_name = key.split(".", 1)
        by_component.setdefault(comp, {})[field_name] = value
    kwargs: dict[str, Any] = {"name": f"{name}+custom"}
    for comp in COMPONENTS:
        current = getattr(base, comp)
        if comp in by_component:
            current = dataclasses.replace(current if current is not None else COMPONENTS[comp](),
                                          **by_component[comp])
        kwargs[comp] = current
    return Instrument(**kwargs)


def _fmt(value: Any) -> str:
    if value is None:
        return "unset"
    if isinstance(value, (tuple, list)):
        return ", ".join(_fmt(v) for v in value) if value else "none"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def parameters_markdown() -> str:
    """Markdown table of every parameter with its flag, unit and the presets' values.

    ``docs/instrument.md`` embeds this table; a test keeps them identical.
    """
    from .presets import PRESETS

    insts = {name: get_preset(name) for name in PRESETS}
    head = "| flag / TOML key | unit | meaning | " + " | ".join(insts) + " |"
    rows = [head, "|" + "---|" * (3 + len(insts))]
    for p in PARAMETERS.values():
        values = []
        for inst in insts.values():
            comp = getattr(inst, p.component)
            values.append("—" if comp is None else _fmt(getattr(comp, p.name)))
        rows.append(f"| `{p.flag}` / `[{p.component}] {p.name}` | {p.unit or '-'} | {p.help} | "
                    + " | ".join(values) + " |")
    return "\n".join(rows) + "\n"
