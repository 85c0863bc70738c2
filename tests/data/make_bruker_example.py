"""Write ``bruker-nanoscope_synthetic.txt``: a SYNTHETIC NanoScope ASCII force-curve export.

Not from an instrument. It imitates the layout of Bruker NanoScope Analysis'
"Export > ASCII" of a ramp (backslash header, ``\\*File list end``, tab-separated
columns named ``<Name>_<unit>_<Ex|Rt>``) so that the reader can be tested:

* data: :func:`afmforce.analysis.synthetic.static_curve` (quasi-static van der
  Waals curve, k = 0.21 N/m, R = 220 nm, InvOLS 45 nm/V, 0.5 um/s), decimated;
* heights in the NanoScope sense (``Calc_Ramp`` and ``PF_Z_Sensor`` *decrease*
  towards the sample), so the reader must flip them;
* the retract columns listed in reverse time order (as NanoScope does), the
  retract run longer than the extend run (empty cells in the Ex columns);
* no Time columns: time comes from ``\\Scan rate``.

Run ``python tests/data/make_bruker_example.py`` to regenerate it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from afmforce.analysis.synthetic import static_curve

SENSITIVITY = 45e-9
DECIMATE = 4

HEADER = r"""\*Force file list
\Version: 0x09300201
\Date: 10:15:02 AM Tue Mar 12 2019
\Note: SYNTHETIC example written by afmforce's tests (tests/data/make_bruker_example.py), not instrument data
\Start context: FOL
\*Scanner list
\Serial Number: 0000 synthetic
\*Ciao force list
\Scan rate: {scan_rate:.6g}
\Forward vel.: 0.5
\Reverse vel.: 0.5
\@Sens. DeflSens: V {sens_nm:.6g} nm/V
\*Ciao force image list
\Samps/line: {n_ex} {n_rt}
\Spring Constant: 0.21
\@4:Image Data: S [DeflectionError] "Deflection Error"
\*File list end
"""


def main(path: Path = Path(__file__).with_name("bruker-nanoscope_synthetic.txt")) -> Path:
    c = static_curve(spring_constant=0.21, radius=220e-9, velocity=0.5e-6, sample_rate=2000.0 * DECIMATE / 4,
                     start=-80e-9, turn=40e-9, sensitivity=SENSITIVITY, offset=0.12, noise=0.03e-9, seed=7)
    seg = c.segment
    ex = np.flatnonzero(seg == 0)[::DECIMATE]
    rt = np.flatnonzero(seg == 1)[::DECIMATE]
    height = -c.piezo_measured  # NanoScope heights decrease towards the sample
    volts = c.deflection_signal
    defl_nm = (volts - 0.12) * SENSITIVITY * 1e9
    cols = {
        "Calc_Ramp_Ex_nm": height[ex] * 1e9, "Calc_Ramp_Rt_nm": height[rt][::-1] * 1e9,
        "Defl_V_Ex": volts[ex], "Defl_V_Rt": volts[rt][::-1],
        "Defl_nm_Ex": defl_nm[ex], "Defl_nm_Rt": defl_nm[rt][::-1],
        "PF_Z_Sensor_nm_Ex": height[ex] * 1e9, "PF_Z_Sensor_nm_Rt": height[rt][::-1] * 1e9,
    }
    n = max(len(v) for v in cols.values())
    scan_rate = 1.0 / ((len(ex) + len(rt)) * DECIMATE / (2000.0 * DECIMATE / 4))
    lines = [HEADER.format(scan_rate=scan_rate, sens_nm=SENSITIVITY * 1e9, n_ex=len(ex), n_rt=len(rt)).rstrip("\n"),
             "\t".join(cols)]
    for i in range(n):
        lines.append("\t".join(f"{v[i]:.6f}" if i < len(v) else "" for v in cols.values()))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


if __name__ == "__main__":
    print(main())
