r"""Write the ``bruker-ascii_*.txt`` files: SYNTHETIC NanoScope Analysis ASCII exports, one per variant.

Not from an instrument. They follow the description of issue 24 of the exports Bruker users share:
every header line wrapped in double quotes (``"\*Force file list"``, ``"\Spring Constant: 0.34"``,
``"\@Sens. DeflSens: V 61.5 nm/V"``, ``"\*File list end"``), then a tab-separated table with columns
``<Quantity>_<unit>_<Ex|Rt>`` or ``<Quantity>_<Ex|Rt>_<unit>``; extend and retract share rows.

The curve is :func:`afmforce.analysis.synthetic.static_curve` (quasi-static van der Waals curve,
k = 0.34 N/m, InvOLS 61.5 nm/V, 1 um/s, 2 kHz, R = 20 nm, 180 samples per run, the same path out and back).
The variants (the tests read :data:`VARIANTS` to know what each file holds):

* ``bruker-ascii_nm_retract-reversed.txt``: ``Calc_Ramp``/``Defl_nm``, heights that decrease towards
  the sample, retract rows in reverse time order, a trailing tab on every data row, CRLF line ends, no
  Time columns (time from ``\Scan rate``);
* ``bruker-ascii_pN_time-columns.txt``: ``Defl_pN``/``Height_Sensor``/``Time_s``, columns in a
  shuffled order with ``Defl_pN_Ex`` twice, retract rows in time order;
* ``bruker-ascii_volts_reversed-time.txt``: ``Defl_V``, ``PF_Z_Sensor`` (increasing towards the
  sample) and ``Calc_Ramp``, retract rows *and* their ``Time_s_Rt`` in reverse, ``Defl_V_Rt`` twice,
  a blank line before the table.

Run ``python tests/data/make_bruker_ascii_variants.py`` to regenerate them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from afmforce.analysis.synthetic import static_curve

K, SENS, OFFSET, RATE = 0.34, 61.5e-9, 0.05, 2000.0
HERE = Path(__file__).parent

#: file -> (columns in file order, retract rows reversed?, sign of the heights towards the sample, CRLF?)
VARIANTS = {
    "bruker-ascii_nm_retract-reversed.txt": (
        ("Calc_Ramp_Ex_nm", "Calc_Ramp_Rt_nm", "Defl_nm_Ex", "Defl_nm_Rt"), True, -1, True),
    "bruker-ascii_pN_time-columns.txt": (
        ("Time_s_Rt", "Defl_pN_Ex", "Height_Sensor_nm_Ex", "Time_s_Ex", "Defl_pN_Rt", "Height_Sensor_nm_Rt",
         "Defl_pN_Ex"), False, -1, False),
    "bruker-ascii_volts_reversed-time.txt": (
        ("Defl_V_Ex", "Defl_V_Rt", "PF_Z_Sensor_nm_Ex", "PF_Z_Sensor_nm_Rt", "Calc_Ramp_Ex_nm", "Calc_Ramp_Rt_nm",
         "Time_s_Ex", "Time_s_Rt", "Defl_V_Rt"), True, +1, False),
}


def source():
    """The curve every variant holds (its time order, SI)."""
    return static_curve(spring_constant=K, radius=20e-9, sensitivity=SENS, offset=OFFSET, velocity=1e-6, sample_rate=RATE,
                        start=-60e-9, turn=30e-9, end=-60e-9, noise=0.02e-9, seed=3)


def columns(c, height_sign: int) -> dict[str, dict[str, np.ndarray]]:
    """Per quantity and run, the values in the file's units, in time order."""
    volts = np.round(c.deflection_signal, 7)       # what is written, so that nm and pN agree with it
    defl_m = (volts - OFFSET) * SENS
    height = height_sign * c.piezo_measured
    out = {}
    for run, sel in (("Ex", c.segment == 0), ("Rt", c.segment == 1)):
        out[run] = {"Calc_Ramp_nm": height[sel] * 1e9, "Height_Sensor_nm": height[sel] * 1e9,
                    "PF_Z_Sensor_nm": height[sel] * 1e9, "Defl_nm": defl_m[sel] * 1e9,
                    "Defl_pN": defl_m[sel] * K * 1e12, "Defl_V": volts[sel], "Time_s": c.time[sel]}
    return out


def split(name: str) -> tuple[str, str]:
    """``Calc_Ramp_Ex_nm`` or ``Defl_nm_Ex`` -> (``Calc_Ramp_nm``/``Defl_nm``, run)."""
    parts = name.split("_")
    run = next(p for p in parts if p in ("Ex", "Rt"))
    return "_".join(p for p in parts if p != run), run


def header(n: int) -> str:
    lines = [r"\*Force file list", r"\Version: 0x09300201", r"\Date: 02:14:51 PM Wed Apr 03 2024",
             r"\Note: SYNTHETIC example written by afmforce's tests (tests/data/make_bruker_ascii_variants.py)",
             r"\*Ciao force list", f"\\Scan rate: {RATE / (2 * n)!r}", r"\Forward vel.: 1", r"\Reverse vel.: 1",
             f"\\@Sens. DeflSens: V {SENS * 1e9:g} nm/V", r"\*Ciao force image list",
             f"\\Samps/line: {n} {n}", f"\\Spring Constant: {K:g}", r"\*File list end"]
    return [f'"{line}"' for line in lines]


def main() -> list[Path]:
    c = source()
    n = int((c.segment == 0).sum())
    written = []
    for name, (cols, reverse, sign, crlf) in VARIANTS.items():
        values = columns(c, sign)
        table = []
        for col in cols:
            qty, run = split(col)
            v = values[run][qty]
            table.append(v[::-1] if reverse and run == "Rt" else v)
        fmt = {"Defl_V": "{:.7f}", "Time_s": "{:.6f}"}
        fmts = [fmt.get(split(col)[0], "{:.5f}") for col in cols]
        tail = "\t" if crlf else ""  # data rows only: one cell more than the column names
        lines = header(n) + ([""] if name.startswith("bruker-ascii_volts") else [])
        lines.append("\t".join(cols))
        lines += ["\t".join(f.format(v[i]) for f, v in zip(fmts, table)) + tail for i in range(n)]
        path = HERE / name
        path.write_bytes(("\r\n" if crlf else "\n").join(lines).encode() + (b"\r\n" if crlf else b"\n"))
        written.append(path)
    return written


if __name__ == "__main__":
    for p in main():
        print(p)
