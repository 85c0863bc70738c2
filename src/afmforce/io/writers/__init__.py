"""Writers of force maps in vendors' formats: what an instrument would have saved.

* :func:`~afmforce.io.writers.jpk_qi.write_jpk_qi`: a JPK QI map (``.jpk-qi-data``: a zip of
  ``header.properties``, ``shared-data/header.properties`` and ``index/<i>/segments/<j>/``),
  read by afmforce's readers and by afmformats/nanite;
* :func:`~afmforce.io.writers.nanoscope_fv.write_nanoscope_fv`: a Bruker NanoScope v9 force volume
  (``.spm``: a text header, then the deflection and Z-sensor channels as 4-byte integers).

Both take the curves one at a time (a generator: a map of any size in constant memory), in
volts (``deflection_unit == "V"``) with approach (segment 0) and retract (segment 1) of one
length each, and write atomically. The virtual AFM's map (:mod:`afmforce.instrument.soft_map`,
``write_soft_map(..., format=...)``) uses them; readers of both formats read the files back with
the calibration (spring constant, sensitivity), grid and curves written (tests/io/test_writers.py).
"""

from __future__ import annotations

from .jpk_qi import write_jpk_qi
from .nanoscope_fv import write_nanoscope_fv

__all__ = ["write_jpk_qi", "write_nanoscope_fv", "WRITERS"]

#: Vendor map writers by the reader identifier that reads their files, with the file ending.
WRITERS = {"jpk-qi": (write_jpk_qi, ".jpk-qi-data"), "bruker-fv": (write_nanoscope_fv, ".spm")}
