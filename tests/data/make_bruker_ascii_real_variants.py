r"""Write NanoScope Analysis ASCII exports of REAL curves, in the variants instruments write (issue 32).

The numbers are two real NanoScope binary force files of this folder, decoded here with numpy from
their bytes and headers (not with afmforce's reader):

* ``bruker-nanoscope_sapphire_TAP525.001`` (TAP525 on sapphire; int16 at offset 40960, Deflection
  Error then Height Sensor, 512 + 512 points each, 0.000375 V/LSB; the Height Sensor x ZsensSens
  960.1708 nm/V), its whole header kept (two ``\Spring Constant`` lines: 90 in the Deflection
  Error list, a stale 0.0677954 in the Height Sensor list);
* ``bruker-nanoscope_PyFMlab_Egel4_00025.spm`` (a gel; int32 at offset 80960, 1024 + 1024 points,
  0.000375 V/LSB; ramp 227.2211 V x Zsens 13.203 nm/V = 3.0 um), every 4th sample.

Both are stored from the turning point: the extend is reversed into time order; the retract rows are
written in reverse (as NanoScope often does), the extend rows in time order.

Variants:

* ``bruker-ascii_sapphire_quoted-crcrlf.txt``: every header line in double quotes, CR CR LF line
  ends, ``Height_Sensor_nm`` and ``Defl_V`` columns;
* ``bruker-ascii_egel_csv-blank-lines.csv``: comma-separated, quoted header lines, quoted column
  names *and* quoted numbers, a blank line after every line (CR CR LF read as two line ends),
  ``Calc_Ramp_Ex_nm`` and ``Defl_nm`` columns;
* ``bruker-ascii_egel_force-separation.txt``: the processed "force vs separation" export only
  (``Separation_nm``, ``Force_nN``), its header without spring constant or sensitivity: force =
  0.1332 N/m x 27.39 nm/V x (V - the median of the first 200 extend samples), separation =
  ramp - deflection, both computed here.

Run ``python tests/data/make_bruker_ascii_real_variants.py`` to regenerate them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
SAPPHIRE = HERE / "bruker-nanoscope_sapphire_TAP525.001"
EGEL = HERE / "bruker-nanoscope_PyFMlab_Egel4_00025.spm"
VLSB = 0.000375  # [V/LSB], both files
K_EGEL, SENS_EGEL, RAMP_EGEL = 0.1332, 27.39e-9, 227.2211 * 13.203e-9  # header values [N/m], [m/V], [m]
ZSENS_SAPPHIRE = 960.1708e-9  # ZsensSens [m/V]


def _header(path: Path) -> list[str]:
    data = path.read_bytes()
    text = data[: data.find(b"\\*File list end")].decode("latin-1")
    return [ln.rstrip("\r") for ln in text.split("\n") if ln.strip()] + ["\\*File list end"]


def _runs(values: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(extend, retract) in time order from a channel stored from the turning point."""
    return values[:n][::-1], values[n:]


def sapphire() -> dict[str, np.ndarray]:
    raw = SAPPHIRE.read_bytes()
    defl = np.frombuffer(raw, "<i2", count=1024, offset=40960) * VLSB
    height = np.frombuffer(raw, "<i2", count=1024, offset=43008) * VLSB * ZSENS_SAPPHIRE
    (d_ex, d_rt), (h_ex, h_rt) = _runs(defl, 512), _runs(height, 512)
    return {"Defl_V_Ex": d_ex, "Defl_V_Rt": d_rt, "Height_Sensor_nm_Ex": h_ex * 1e9, "Height_Sensor_nm_Rt": h_rt * 1e9}


def egel() -> dict[str, np.ndarray]:
    volts = np.frombuffer(EGEL.read_bytes(), "<i4", count=2048, offset=80960) * VLSB
    v_ex, v_rt = _runs(volts, 1024)
    z_ex = np.linspace(0.0, RAMP_EGEL, 1024, endpoint=False) + RAMP_EGEL / 1024  # towards the sample
    z_rt = RAMP_EGEL - np.arange(1024) * (RAMP_EGEL / 1024)
    base = np.median(v_ex[:200])
    out = {}
    for run, v, z in (("Ex", v_ex[::4], z_ex[::4]), ("Rt", v_rt[::4], z_rt[::4])):
        d = (v - base) * SENS_EGEL
        out.update({f"Calc_Ramp_{run}_nm": -z * 1e9, f"Defl_nm_{run}": d * 1e9,  # heights fall towards the sample
                    f"Force_nN_{run}": d * K_EGEL * 1e9, f"Separation_nm_{run}": (RAMP_EGEL - z + d) * 1e9})
    return out


def _rows(columns: dict[str, np.ndarray], names: list[str], fmt: str) -> list[list[str]]:
    cols = [columns[c][::-1] if c.endswith("Rt") or "_Rt_" in c else columns[c] for c in names]  # retract reversed
    return [[fmt.format(col[i]) for col in cols] for i in range(len(cols[0]))]


def main() -> list[Path]:
    written = []
    s = sapphire()
    names = ["Height_Sensor_nm_Ex", "Height_Sensor_nm_Rt", "Defl_V_Ex", "Defl_V_Rt"]
    lines = [f'"{ln}"' for ln in _header(SAPPHIRE)] + ["\t".join(names)]
    lines += ["\t".join(r) for r in _rows(s, names, "{:.6f}")]
    path = HERE / "bruker-ascii_sapphire_quoted-crcrlf.txt"
    path.write_bytes(("\r\r\n".join(lines) + "\r\r\n").encode("latin-1"))
    written.append(path)

    e = egel()
    keep = ("\\*Force file list", "\\Version", "\\Date", "\\*Ciao force list", "\\Scan rate", "\\Samps/line",
            "\\@Sens. DeflSens", "\\*Ciao force image list", "\\Spring Constant", "\\@4:Image Data", "\\*File list end")
    head = [ln for ln in _header(EGEL) if ln.startswith(keep)]
    names = ["Calc_Ramp_Ex_nm", "Calc_Ramp_Rt_nm", "Defl_nm_Ex", "Defl_nm_Rt"]
    lines = ['"' + ln.replace('"', '""') + '"' for ln in head] + [",".join(f'"{n}"' for n in names)]
    lines += [",".join(f'"{c}"' for c in r) for r in _rows(e, names, "{:.5f}")]
    path = HERE / "bruker-ascii_egel_csv-blank-lines.csv"
    path.write_bytes(("\r\n\r\n".join(lines) + "\r\n\r\n").encode("latin-1"))
    written.append(path)

    head = [ln for ln in head if not ln.startswith(("\\Spring Constant", "\\@Sens. DeflSens"))]
    names = ["Separation_nm_Ex", "Force_nN_Ex", "Separation_nm_Rt", "Force_nN_Rt"]
    lines = [f'"{ln}"' for ln in head] + ["\t".join(names)] + ["\t".join(r) for r in _rows(e, names, "{:.5f}")]
    path = HERE / "bruker-ascii_egel_force-separation.txt"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("latin-1"))
    written.append(path)
    return written


if __name__ == "__main__":
    for p in main():
        print(p, p.stat().st_size)
