"""Older JPK text exports (SPM 3/4, 2011; corpus5): philippoertle/forcecurve_analysis' connective-tissue map
curves ``map-data-2011.04.19-13.41.43-{0000,0273}.out`` (no licence stated, not redistributed) mark their two
blocks ``# direction: trace`` / ``# direction: retrace`` instead of ``# segment: extend`` / ``retract``, and
store the retrace from its far end back to the turning point (``seriesTime`` falling). afmforce found "content
not recognised" (and with ``--format jpk-txt``: "no '# segment:' block"); it reads them now: the trace is the
approach, the retrace the retract in time order. The file is written here in that layout with known rows."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.io import find_format, load

HEAD = """# index: 0
# xPosition: -3.4391555167956884E-5
# forceSettings: relative
# kLength: 668
# date: Tue Apr 19 13:41:42 CEST 2011
#
# direction: {direction}
# columns: smoothedStrainGaugeHeight vDeflection strainGaugeHeight height hDeflection seriesTime time
# heightMultiplier: 0.62561
# heightOffset: 0.0
# sensitivity: 4.189520424555576E-8
# springConstant: 0.08
# calibrationSlots: nominal force nominal nominal volts elapsed elapsed
# units: m N m m V s s
#
"""


def _rows(h, f, t, t0):
    return "".join(f"{a:.8E} {b:.8E} {a:.8E} {a / 0.62561:.8E} -0.05 {c:.8E} {c - t0:.8E}\n" for a, b, c in zip(h, f, t))


def test_trace_and_retrace_blocks_read_as_approach_and_retract_in_time_order(tmp_path):
    n, dt = 200, 4.8828125e-4
    h_app = np.linspace(14e-6, 12e-6, n)                      # the head comes down
    f_app = np.clip(12.5e-6 - h_app, 0, None) * 0.02          # [N]
    t_app = (np.arange(n) + 0.5) * dt
    t_ret = t_app[-1] + (np.arange(n) + 1) * dt
    h_ret, f_ret = h_app[::-1], f_app[::-1] * 0.9
    text = (HEAD.format(direction="trace") + _rows(h_app, f_app, t_app, 0.0) + "\n"
            + HEAD.format(direction="retrace") + _rows(h_ret[::-1], f_ret[::-1], t_ret[::-1], t_ret[0]))
    path = tmp_path / "map-data-2011.04.19-13.41.43-0000.out"
    path.write_text(text)
    assert find_format(path).identifier == "jpk-txt"
    (c,) = load(path)
    assert (c.approach.sum(), c.retract.sum()) == (n, n)
    assert c.deflection_unit == "N"
    np.testing.assert_allclose(c.deflection_signal[c.approach], f_app, rtol=1e-7, atol=1e-20)
    np.testing.assert_allclose(c.deflection_signal[c.retract], f_ret, rtol=1e-7, atol=1e-20)
    np.testing.assert_allclose(c.time, np.concatenate([t_app, t_ret]), rtol=1e-7)
    assert np.all(np.diff(c.time) > 0)
    md = c.metadata
    assert md["spring_constant"] == 0.08 and md["sensitivity"] == pytest.approx(4.189520424555576e-8)
    assert md["sample_rate"] == pytest.approx(1 / dt, rel=1e-6)
    # the height is the calibrated slot: nominal x heightMultiplier (here the measured column's values)
    assert np.ptp(c.piezo_nominal[c.approach]) == pytest.approx(2e-6, rel=1e-6)
    assert "position_note" not in md   # the strain gauge spans the nominal x heightMultiplier: nothing to say


@pytest.mark.parametrize("scale, said", ((1.0, False), (1.05, False), (1.5, True)))
def test_a_strain_gauge_far_off_the_nominal_height_is_said(tmp_path, scale, said):
    """The 2011 map curves' strain gauge spans 1.53 x the nominal height x heightMultiplier over the trace
    (11.28 vs 7.53 um on ``-0000.out``) and afmforce said nothing; beyond the tolerance the Bruker reader
    declares for its Z sensor (``SENSOR_RAMP_TOLERANCE``, 10 %) the reader now says it (``position_note``,
    among the analysis's warnings when the measured height is the position used). The file is written here
    with the strain gauge ``scale`` x the calibrated height, a constant ratio."""
    from afmforce.io._meta import SENSOR_RAMP_TOLERANCE

    n, dt = 200, 4.8828125e-4
    h = np.linspace(14e-6, 12e-6, n)
    f = np.clip(12.5e-6 - h, 0, None) * 0.02 + 1e-11 * np.random.default_rng(0).standard_normal(n)
    t = (np.arange(2 * n) + 0.5) * dt

    def rows(h, f, t):
        return "".join(f"{scale * a:.8E} {b:.8E} {scale * a:.8E} {a / 0.62561:.8E} -0.05 {c:.8E} {c:.8E}\n"
                       for a, b, c in zip(h, f, t))

    path = tmp_path / "map-data-2011.04.19-13.41.43-0001.out"
    path.write_text(HEAD.format(direction="trace") + rows(h, f, t[:n]) + "\n"
                    + HEAD.format(direction="retrace") + rows(h[::-1], f[::-1] * 0.9, t[n:]))
    (c,) = load(path)
    ratio = np.ptp(c.piezo_measured[c.approach]) / np.ptp(c.piezo_nominal[c.approach])
    assert ratio == pytest.approx(scale, rel=1e-6)   # independently: the two spans written
    assert (abs(ratio - 1) > SENSOR_RAMP_TOLERANCE) == said
    note = c.metadata.get("position_note")
    assert (note is not None) == said
    if said:
        assert note.startswith("the measured height (strainGaugeHeight) travels 1.5 x the nominal ramp (2000 nm = "
                               "height x heightMultiplier)") and "a constant ratio" in note
        from afmforce.analysis.pipeline import analyze
        assert note in analyze(c).warnings   # the measured height is the position used: the analysis says it
