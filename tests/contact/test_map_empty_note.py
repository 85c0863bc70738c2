"""A map quantity no curve gave is all "no value" (NaN, never zeros) and says why, in one CLI line,
on the PNG and in the HDF5 (the web's map JSON: tests/web/test_web_map_note.py).

Was: ``afmforce analyze MAP --map-quantity modulus`` on a Tap150Al map of a hard surface (the
Nanosurf 10 x 10 map, and its trimmed 2 x 2 here) wrote a grey image titled "0 of 100 points" with a
-0.1..0.1 kPa colour bar and said nothing: the indentation fit skips hard contacts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from afmforce.analysis.maps import map_images

DATA = Path(__file__).resolve().parents[1] / "data"
NID = DATA / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid"


def _table(kinds, errors, modulus):
    n = len(kinds)
    return pd.DataFrame({"file": "m.nid", "curve": range(n), "map_x": [i % 2 for i in range(n)],
                         "map_y": [i // 2 for i in range(n)], "map_nx": 2, "map_ny": 2,
                         "contact_kind": kinds, "error": errors, "youngs_modulus": modulus})


def test_the_note_counts_the_contact_kinds_and_failures():
    (image,) = map_images(_table(["hard", "hard", None, "hard"], [None, None, "FileFormatError: x", None],
                                 [np.nan] * 4), "modulus")
    assert np.isnan(image.values).all()
    assert image.note.startswith("no curve gave it (4 curves: 1 failed, 3 hard contacts); it comes from soft")
    (some,) = map_images(_table(["soft", "hard", "hard", "hard"], [None] * 4, [1e3, np.nan, np.nan, np.nan]),
                         "modulus")
    assert some.note == "" and np.isfinite(some.values).sum() == 1


def test_the_cli_says_why_a_hard_maps_modulus_map_is_empty(tmp_path, capsys):
    import h5py

    from afmforce.cli.main import main

    out = tmp_path / "out"
    code = main(["analyze", str(NID), "--out", str(out), "--map-quantity", "modulus",
                 "--map-quantity", "adhesion"])
    err = capsys.readouterr().err
    assert code == 0
    notes = [ln for ln in err.splitlines() if ln.startswith("note:")]
    assert notes == [f"note: {NID.name}: map of modulus empty: no curve gave it (4 curves: 4 hard contacts); "
                     "it comes from soft contacts: the indentation fit skips hard ones (the tip does not "
                     "indent the sample)"]
    (h5path,) = out.rglob("*.maps.h5")
    with h5py.File(h5path) as h5:
        assert np.isnan(h5["modulus"][()]).all() and "hard contacts" in h5["modulus"].attrs["note"]
        assert np.isfinite(h5["adhesion"][()]).all() and "note" not in h5["adhesion"].attrs
    assert len(list(out.rglob("*.modulus.png"))) == 1


def test_without_map_quantity_every_default_quantity_some_curve_gave_is_mapped(tmp_path, capsys):
    """Was: only the adhesion map (``--map-quantity`` needed for the modulus and topography a user
    expects of a soft map, issue 35 item 6). Now each of ``DEFAULT_MAPS`` that some curve gave; on this
    hard map the adhesion and A R, and no empty modulus image nor a note about it."""
    from afmforce.analysis.maps import DEFAULT_MAPS, map_images
    from afmforce.cli.main import main

    out = tmp_path / "out"
    assert main(["analyze", str(NID), "--out", str(out)]) == 0
    assert "note:" not in capsys.readouterr().err
    (folder,) = out.glob("batch-*")
    table = pd.read_parquet(folder / "summary.parquet")
    gave = {q for q in DEFAULT_MAPS if any(not im.note for im in map_images(table, q))}
    assert {"adhesion", "hamaker_radius"} <= gave and "modulus" not in gave
    drawn = {p.name[len(NID.name) + 1:-4] for p in folder.glob("*.png") if not p.name.endswith(".hist.png")}
    assert drawn == gave
