"""A curve whose time stamps repeat (a map curve thinned, an export with coarse time) is analysed:
the oscillation step has no Nyquist frequency there instead of raising ZeroDivisionError."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np

from afmforce.analysis.pipeline import analyze
from afmforce.io import load

MAP = Path(__file__).resolve().parents[1] / "data" / "afmforce-map_jpk-map2x2.h5"


def test_repeated_time_stamps_do_not_break_the_analysis():
    curve = load(MAP)[0]
    idx = np.linspace(0, curve.time.size - 1, 300).round().astype(int)
    arrays = {f.name: getattr(curve, f.name)[idx] for f in dataclasses.fields(curve)
              if isinstance(getattr(curve, f.name), np.ndarray) and getattr(curve, f.name).shape == curve.time.shape}
    time = arrays["time"].copy()
    time[1::2] = time[0::2][: time[1::2].size]          # every second sample repeats its predecessor's time
    thin = dataclasses.replace(curve, **{**arrays, "time": time})
    assert np.median(np.diff(time)) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = analyze(thin)                              # was: ZeroDivisionError in the oscillation step
    osc = res.details.get("oscillation")
    if osc is not None:
        for peak in (osc.approach, osc.retract):
            assert math.isnan(peak.nyquist) or peak.nyquist > 0
