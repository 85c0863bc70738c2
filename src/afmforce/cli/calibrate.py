"""``afmforce calibrate``: the probe's spring constant, resonance, Q and InvOLS (docs/calibration.md).

* ``afmforce calibrate thermal FILE`` -- a thermal spectrum (JPK ``.tnd``, afmforce ``.psd``):
  simple-harmonic-oscillator fit, equipartition (temperature, correction, tilt: given or the file's);
* ``afmforce calibrate sader --length --width --frequency --quality-factor --medium`` -- the Sader
  method for a rectangular lever, or the general method with a reference lever;
* ``afmforce calibrate invols FILE`` -- the InvOLS from the compliance line of a force curve.

``--out calib.json`` writes the result for ``afmforce analyze --probe-calibration`` and
``afmforce simulate --probe-calibration``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math

from ..errors import AnalysisError, ParameterError
from ..constants import DEFAULT_TEMPERATURE, SADER_FLUIDS as FLUIDS
from ._validate import add_field, check_outputs
from ._outcome import render
from .common import eprint, print_json, print_table


def _common(p, method: bool = True) -> None:
    """--out, --force, --json: on ``calibrate`` and on each method (where a default would
    override the value given before the method's name, argparse.SUPPRESS keeps it)."""
    keep = {"default": argparse.SUPPRESS} if method else {}
    p.add_argument("--out", metavar="FILE", help="write the calibration (JSON) for analyze/simulate "
                   "--probe-calibration", **(keep or {"default": None}))
    p.add_argument("--force", action="store_true", help="overwrite --out if it exists", **keep)
    p.add_argument("--json", action="store_true", help="print one JSON object with SI values", **keep)


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="calibrate the probe: thermal noise spectrum, Sader method, InvOLS",
                       description="Calibrate the probe (docs/calibration.md): the spring constant, resonance "
                                   "and quality factor from a thermal spectrum or the Sader method, the InvOLS "
                                   "from a force curve's compliance line.")
    _common(p, method=False)
    kinds = p.add_subparsers(dest="method", metavar="METHOD")

    t = kinds.add_parser("thermal", help="thermal noise spectrum: SHO fit and equipartition",
                         description="Fit a simple harmonic oscillator with a white (and optionally 1/f) "
                                     "background to the first mode of a thermal spectrum; k = chi kB T / <z^2>.")
    t.add_argument("file", nargs="?", help="thermal spectrum: JPK .tnd, afmforce .psd, or two columns of text "
                   "(frequency in Hz, spectrum)")
    t.add_argument("--example", default=None, metavar="NAME",
                   help="a shipped spectrum instead of FILE: virtual-air (simulated), jpk-water (real)")
    add_field(t, "temperature", help=f"temperature (default: the file's, else the room, {DEFAULT_TEMPERATURE:g} K)")
    add_field(t, "sensitivity", flag="--invols", help="InvOLS for a spectrum in V^2/Hz (default: the file's)")
    add_field(t, "equipartition_correction", flag="--correction",
              help="chi of k = chi kB T/<z^2> (default: the file's, else 0.817, Butt & Jaschke)")
    add_field(t, "lever_tilt", flag="--tilt", help="lever tilt: also report k/cos^2 normal to the sample "
              "(default: the file's, else 0)")
    add_field(t, "frequency_min", help="lowest frequency fitted (default: from the peak)")
    add_field(t, "frequency_max", help="highest frequency fitted (default: from the peak)")
    t.add_argument("--pink", action="store_true", help="fit a 1/f background term as well")
    t.add_argument("--plot", metavar="FILE.png", default=None, help="draw the spectrum and the fit")
    t.add_argument("--psd-unit", default=None, choices=("m^2/Hz", "V^2/Hz", "m/sqrt(Hz)", "V/sqrt(Hz)"),
                   help="unit of a plain two-column text spectrum whose header does not state it")
    t.add_argument("--medium", default=None, choices=tuple(FLUIDS),
                   help="medium, for the Sader cross-check with --length/--width (default: the file's)")
    add_field(t, "lever_length", flag="--length", help="lever length, for a Sader cross-check")
    add_field(t, "lever_width", flag="--width", help="lever width, for a Sader cross-check")
    _common(t)
    t.set_defaults(func=run_thermal)

    s = kinds.add_parser("sader", help="Sader method: rectangular lever, or general with a reference",
                         description="k = 0.1906 rho b^2 L Q Gamma_i(Re) (2 pi f)^2 (Sader 1999), or the general "
                                     "method k = A rho^(1-a) eta^a Q f^(2-a) (Sader 2012) calibrated on a reference.")
    add_field(s, "lever_length", flag="--length")
    add_field(s, "lever_width", flag="--width")
    add_field(s, "resonance_frequency", flag="--frequency", help="resonance frequency in the medium")
    add_field(s, "quality_factor", help="quality factor in the medium")
    s.add_argument("--medium", default="air", choices=tuple(FLUIDS), help="medium (default air)")
    add_field(s, "density", help="density of the medium (default: the preset's)")
    add_field(s, "viscosity", help="viscosity of the medium (default: the preset's)")
    g = s.add_argument_group("general method (any plan view): a reference lever of the same type")
    add_field(g, "reference_spring_constant")
    add_field(g, "reference_frequency")
    add_field(g, "reference_quality_factor")
    add_field(g, "sader_exponent", flag="--exponent", help="exponent a (default: from --width)")
    _common(s)
    s.set_defaults(func=run_sader)

    i = kinds.add_parser("invols", help="InvOLS from the compliance line of a force curve",
                         description="The optical-lever sensitivity 1/slope of the constant-compliance line "
                                     "(a calibration curve on a hard surface, deflection in volts).")
    i.add_argument("file", nargs="?", help="force-curve file")
    i.add_argument("--example", action="store_true", help="the shipped JPK calibration curve (raw volts)")
    i.add_argument("--run", choices=("approach", "retract"), default="approach",
                   help="compliance line used (default approach)")
    i.add_argument("--format", default=None, help="reader (afmforce formats lists them)")
    _common(i)
    i.set_defaults(func=run_invols)

    v = kinds.add_parser("virtual", help="record the thermal spectrum of a virtual lever (known k)",
                         description="The virtual AFM's thermal tune: the thermal spectrum of the spring or the "
                                     "beam probe (both free modes) with the lever's damping, averaged periodograms "
                                     "over a white floor, written in the afmforce spectrum format (.psd).")
    v.add_argument("--model", choices=("spring", "beam"), default="spring", help="probe (default spring)")
    add_field(v, "spring_constant", default=0.2, help="spring constant k (spring model)")
    add_field(v, "resonance_frequency", default=20e3, help="resonance frequency (spring model)")
    add_field(v, "quality_factor", default=50.0, help="quality factor (beam: both modes unless "
              "--quality-factor-2)")
    add_field(v, "quality_factor_2", help="quality factor of the beam's second mode")
    add_field(v, "temperature", default=DEFAULT_TEMPERATURE)     # the one lab temperature of calibrate (constants)
    v.add_argument("--averages", type=int, default=64, help="periodograms averaged (default %(default)s)")
    v.add_argument("--white", type=float, default=1e-27, metavar="M2_PER_HZ",
                   help="white detector floor [m^2/Hz] (default %(default)g)")
    v.add_argument("--seed", type=int, default=0, help="random seed (default %(default)s)")
    v.add_argument("--spectrum", metavar="FILE.psd", required=True, help="the spectrum file to write")
    _common(v)
    v.set_defaults(func=run_virtual)
    p.set_defaults(func=_no_method)


def _no_method(args) -> int:
    raise ParameterError("choose a method: afmforce calibrate thermal|sader|invols|virtual (--help for each)")


def _finish(args, method: str, values: dict, units: dict, rows: list, title: str, verdict: str = "") -> int:
    if args.out:
        from ..calibration.record import write_calibration

        write_calibration(args.out, method, values, units, force=args.force)
    if args.json:
        print_json({"method": method, **values, "units": units})
        return 0
    print_table([(label, (value if isinstance(value, str) else f"{value:.5g}") + (f" {unit}" if unit else ""), "")
                 for label, value, unit in rows], title=title)
    if verdict:
        print(f"  {verdict}")
    return 0


def _check_out(args, *more: tuple[str, str | None]) -> None:
    """Refuse, before any work (exit 2), an --out (and the ``more`` ``(flag, path)`` outputs) that cannot
    be written, that two of them name the same file, or that one is the file read."""
    check_outputs([("--out", args.out), *more], force=args.force,
                  inputs=(getattr(args, "file", None), getattr(args, "probe_calibration", None)))


def run_thermal(args: argparse.Namespace) -> int:
    _check_out(args, ("--plot", args.plot))
    from ..calibration import BUTT_JASCHKE, DEFAULT_TEMPERATURE, fit_thermal, read_spectrum
    from ..calibration.thermal import ThermalFit
    from ._outcome import RunState

    RunState.flags.update(sensitivity="--invols")   # this command's flag for the InvOLS (the library's `sensitivity`)

    if (args.file is None) == (args.example is None):
        raise ParameterError("give a thermal spectrum FILE or --example NAME (virtual-air, jpk-water)")
    if args.example is not None:
        from ..datasets import thermal_example

        path = thermal_example(args.example)
    else:
        path = args.file
    from ..errors import MissingMetadataError

    try:
        sp = read_spectrum(path, unit=args.psd_unit)
    except MissingMetadataError as exc:
        if "psd_unit" not in exc.keys:
            raise
        raise MissingMetadataError(str(exc).replace("(psd_unit)", "with --psd-unit"), exc.keys,
                                   ("--psd-unit",)) from None
    sources = {}

    def pick(name, given, stored, default, what):
        if given is not None:
            sources[name] = "given"
            return given
        if stored is not None:
            sources[name] = "file"
            return stored
        sources[name] = f"default ({what})"
        return default

    temperature = pick("temperature", args.temperature, sp.temperature, DEFAULT_TEMPERATURE,
                       f"{DEFAULT_TEMPERATURE:g} K, the room")
    correction = pick("correction", args.equipartition_correction, sp.correction, BUTT_JASCHKE,
                      "0.817, Butt & Jaschke: optical lever, static InvOLS")
    tilt = pick("tilt", args.lever_tilt, sp.tilt, 0.0, "no tilt")
    sensitivity = None
    if sp.unit == "V^2/Hz":
        sensitivity = pick("sensitivity", args.sensitivity, sp.sensitivity, None, "none")
        if sensitivity is None:
            raise ParameterError("the spectrum is in V^2/Hz and stores no InvOLS; give --invols (e.g. 50nm/V)")
    elif args.sensitivity is not None:
        raise ParameterError("--invols is for spectra in V^2/Hz; this one is in m^2/Hz already")
    f_range = None
    if args.frequency_min is not None or args.frequency_max is not None:
        lo = args.frequency_min or 0.0
        hi = args.frequency_max or float(sp.frequency[-1])
        if not lo < hi:
            raise ParameterError(f"--frequency-min {lo:g} Hz must lie below --frequency-max {hi:g} Hz")
        f_range = (lo, hi)
    elif sp.window is not None:   # the window the instrument fitted (a Nanosurf thermal tune's)
        f_range = sp.window
        sources["window"] = "file"
    fit = fit_thermal(sp.frequency, sp.displacement_psd(sensitivity), temperature=temperature,
                      correction=correction, tilt=tilt, f_range=f_range, pink=args.pink, averages=sp.averages)
    if args.plot:
        from ..plotting.calibration import write_thermal_png

        write_thermal_png(sp.frequency, sp.displacement_psd(sensitivity), fit, args.plot, force=args.force)
    values = {f: getattr(fit, f) for f in ThermalFit.UNITS}
    units = dict(ThermalFit.UNITS)
    values["sensitivity"] = sensitivity
    units["sensitivity"] = "m/V"
    values["sources"] = sources
    values["file"] = str(path)
    vendor_k = sp.vendor.get("spring_constant")
    if vendor_k:
        values["file_spring_constant"] = vendor_k
        values["file_spring_constant_ratio"] = fit.spring_constant / vendor_k
        units["file_spring_constant"] = "N/m"
        units["file_spring_constant_ratio"] = ""
    length = args.lever_length if args.lever_length is not None else sp.vendor.get("length")
    width = args.lever_width if args.lever_width is not None else sp.vendor.get("width")
    medium = args.medium or sp.medium
    if length and width and medium in FLUIDS:
        from ..calibration import sader_rectangular

        try:
            sader = sader_rectangular(length, width, fit.resonance_frequency, fit.quality_factor, medium)
        except (ParameterError, AnalysisError) as exc:   # a lever the method does not describe: no Sader k
            eprint(f"warning: no Sader k: {render(str(exc))}")
        else:
            values["spring_constant_sader"] = sader.spring_constant
            units["spring_constant_sader"] = "N/m"
    rows = [("spring constant k", _pm(fit.spring_constant, fit.spring_constant_se, 1e3), "mN/m"),
            ("resonance frequency", _pm(fit.resonance_frequency, fit.resonance_frequency_se, 1e-3), "kHz"),
            ("quality factor Q", _pm(fit.quality_factor, fit.quality_factor_se, 1.0), ""),
            ("<z^2> of the mode", fit.mean_square * 1e24, "pm^2"),
            ("temperature", f"{temperature:.2f} K ({sources['temperature']})", ""),
            ("correction chi", f"{correction:.4g} ({sources['correction']})", "")]
    if tilt:
        rows.append(("k normal to the sample", fit.spring_constant_normal * 1e3, f"mN/m (tilt {math.degrees(tilt):.3g} deg)"))
    if sensitivity is not None:
        rows.append(("InvOLS", f"{sensitivity * 1e9:.5g} nm/V ({sources['sensitivity']})", ""))
    rows.append(("window fitted", f"{fit.f_min * 1e-3:.4g} - {fit.f_max * 1e-3:.4g} kHz ({fit.n_bins} bins)", ""))
    rows.append(("averages (from scatter), deviance", f"{fit.averages:.3g}, {fit.reduced_deviance:.3g}", ""))
    if fit.spring_constant_se_window > 0.25 * fit.spring_constant_se:
        rows.append(("k's error from the window", f"{fit.spring_constant_se_window * 1e3:.2g} mN/m (in the +-)", ""))
    if fit.masked:
        rows.append(("electrical lines masked", fit.masked, "bins"))
    if vendor_k:
        rows.append(("the file's k", f"{vendor_k * 1e3:.5g} mN/m (ratio {fit.spring_constant / vendor_k:.4f})", ""))
    if "spring_constant_sader" in values:
        rows.append(("Sader k (f0, Q fitted)", values["spring_constant_sader"] * 1e3, "mN/m"))
    return _finish(args, "thermal", values, units, rows, f"afmforce calibrate thermal {path}")


def _pm(value: float, se: float, scale: float) -> str:
    if not math.isfinite(se) or se <= 0:
        return f"{value * scale:.5g}"
    return f"{value * scale:.5g} +- {se * scale:.2g}"


def run_sader(args: argparse.Namespace) -> int:
    _check_out(args)
    from ..calibration.sader import (SaderResult, general_constant, sader_general, sader_rectangular)

    if args.resonance_frequency is None or args.quality_factor is None:
        raise ParameterError("give --frequency and --quality-factor (the lever's resonance in its medium)")
    refs = (args.reference_spring_constant, args.reference_frequency, args.reference_quality_factor)
    general = any(v is not None for v in refs)
    if general:
        if any(v is None for v in refs):
            raise ParameterError("the general method needs --reference-spring-constant, --reference-frequency "
                                 "and --reference-quality-factor")
        const = general_constant(*refs, args.medium, exponent=args.sader_exponent, width=args.lever_width,
                                 density=args.density, viscosity=args.viscosity)
        res = sader_general(args.resonance_frequency, args.quality_factor, const, args.medium,
                            density=args.density, viscosity=args.viscosity)
        extra = {"constant": const.constant, "exponent": const.exponent}
    else:
        if args.lever_length is None or args.lever_width is None:
            raise ParameterError("give --length and --width of the rectangular lever (or a reference lever "
                                 "for the general method)")
        res = sader_rectangular(args.lever_length, args.lever_width, args.resonance_frequency,
                                args.quality_factor, args.medium, density=args.density, viscosity=args.viscosity)
        extra = {}
    values = {f: getattr(res, f) for f in SaderResult.UNITS}
    values.update(resonance_frequency=args.resonance_frequency, quality_factor=args.quality_factor, **extra)
    units = {**SaderResult.UNITS, "resonance_frequency": "Hz", "quality_factor": "", "constant": "SI",
             "exponent": ""}
    rows = [("spring constant k", res.spring_constant * 1e3, "mN/m"), ("method", res.method, ""),
            ("medium", f"{args.medium}: {res.density:.5g} kg/m^3, {res.viscosity:.4g} Pa s", "")]
    if not general:
        rows += [("Reynolds number", res.reynolds_number, ""),
                 ("Gamma (real, imag)", f"{res.gamma_real:.5g}, {res.gamma_imag:.5g}", "")]
    else:
        rows += [("constant A, exponent a", f"{extra['constant']:.5g}, {extra['exponent']:.4g}", "")]
    return _finish(args, "sader", values, units, rows, "afmforce calibrate sader")


def run_invols(args: argparse.Namespace) -> int:
    _check_out(args)
    from ..analysis.invols import InvolsResult, measure_invols
    from ..analysis import units_of
    from ..io import load

    if (args.file is None) == (not args.example):
        raise ParameterError("give a force-curve FILE or --example")
    if args.example:
        from ..datasets import path as example_path

        path = example_path("jpk-calibration")
    else:
        path = args.file
    curves = load(path, format=args.format)
    results = [measure_invols(c, run=args.run) for c in curves]
    r = results[0]
    units = units_of(r)
    values = {f.name: getattr(r, f.name) for f in dataclasses.fields(InvolsResult)}
    values["file"] = str(path)
    if len(results) > 1:
        values["curves"] = [dataclasses.asdict(x) for x in results]
    if not r.determined:  # a number the curve did not determine: no interval, and none handed on
        values["sensitivity_se"] = None
    rows = [("InvOLS", _pm(r.sensitivity, r.sensitivity_se, 1e9), "nm/V") if r.determined else
            ("InvOLS", f"undetermined (the {r.run} line alone: {r.sensitivity * 1e9:.5g} nm/V)", ""),
            ("approach / retract", f"{r.sensitivity_approach * 1e9:.5g} / {r.sensitivity_retract * 1e9:.5g}", "nm/V"),
            ("samples in the line", r.n_points, "")]
    if math.isfinite(r.file_sensitivity):
        rows.append(("the file's InvOLS", r.file_sensitivity * 1e9, "nm/V"))
    if len(results) > 1:
        rows.append(("curves", len(results), "(the first shown; --json lists each)"))
    return _finish(args, "invols", values, units, rows, f"afmforce calibrate invols {path}", r.verdict)


def add_probe_calibration_flag(group, takes: str = "spring constant, sensitivity, resonance frequency") -> None:
    """``--probe-calibration FILE`` for analyze, simulate and fit (a file of ``calibrate --out``)."""
    group.add_argument("--probe-calibration", dest="probe_calibration", metavar="FILE", default=None,
                       help=f"probe values from 'afmforce calibrate ... --out FILE': {takes}; flags given "
                            "explicitly win")


def fill_from_calibration(args: argparse.Namespace, names) -> dict:
    """Set ``args.<name>`` from the calibration file where the user gave none; returns what was set."""
    path = getattr(args, "probe_calibration", None)
    if not path:
        return {}
    from ..calibration.record import read_calibration

    values = read_calibration(path)
    used = {n: values[n] for n in names if n in values and getattr(args, n, None) is None}
    for name, value in used.items():
        setattr(args, name, value)
    return used


def calibrated_probe(args: argparse.Namespace) -> dict:
    """``simulate --probe-calibration``: the quality factor for either model; for the spring
    model also k and the mass ``k / (2 pi f0)^2`` that gives the calibrated resonance."""
    if not getattr(args, "probe_calibration", None):
        return {}
    used = fill_from_calibration(args, ("quality_factor",))
    if getattr(args, "model", None) == "spring":
        from ..calibration.record import read_calibration

        values = read_calibration(args.probe_calibration)
        used.update(fill_from_calibration(args, ("spring_constant",)))
        f0 = values.get("resonance_frequency")
        if f0 and getattr(args, "mass", None) is None and args.spring_constant is not None:
            args.mass = args.spring_constant / (2.0 * math.pi * f0) ** 2
            used["mass"] = args.mass
    return used


def run_virtual(args: argparse.Namespace) -> int:
    from ..calibration import write_spectrum
    from ..dynamics.parts import BeamProbe, SpringProbe
    from ..dynamics.thermal import thermal_spectrum

    _check_out(args, ("--spectrum", args.spectrum))
    if args.averages < 1:
        raise ParameterError(f"--averages must be at least 1, got {args.averages}")
    if not (math.isfinite(args.white) and args.white >= 0):    # inf wrote a spectrum of infinite bins
        raise ParameterError(f"--white must be a finite, non-negative PSD [m^2/Hz], got {args.white}")
    if args.model == "spring":
        if args.quality_factor_2 is not None:
            raise ParameterError("--quality-factor-2 is the beam's second mode; the spring has one")
        k = args.spring_constant
        probe = SpringProbe(spring_constant=k, mass=k / (2 * math.pi * args.resonance_frequency) ** 2,
                            quality_factor=args.quality_factor)
    else:
        probe = BeamProbe(quality_factor=args.quality_factor, quality_factor_2=args.quality_factor_2)
    sp = thermal_spectrum(probe, temperature=args.temperature, averages=args.averages, white=args.white,
                          seed=args.seed)
    write_spectrum(args.spectrum, sp, force=args.force)
    values = {"spring_constant": float(probe.force_constant), "resonance_frequency": sp.vendor["resonance_frequency"],
              "quality_factor": args.quality_factor, "correction": sp.correction, "temperature": args.temperature,
              "bins": int(sp.frequency.size), "spectrum": str(args.spectrum)}
    units = {"spring_constant": "N/m", "resonance_frequency": "Hz", "quality_factor": "", "correction": "",
             "temperature": "K", "bins": ""}
    rows = [("probe", args.model, ""), ("spring constant k (truth)", probe.force_constant * 1e3, "mN/m"),
            ("first mode", sp.vendor["resonance_frequency"] * 1e-3, "kHz"),
            ("first mode's share chi", sp.correction, ""),
            ("bins", f"{sp.frequency.size} up to {sp.frequency[-1] * 1e-3:.4g} kHz", "")]
    return _finish(args, "virtual", values, units, rows, f"afmforce calibrate virtual -> {args.spectrum}")
