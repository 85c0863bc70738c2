"""Refusals that explain (issue 32, item 8): every file a reader cannot read is refused with which
reader tried, what it found unexpected and what to do (another reader of the ending, metadata the
file lacks, a report), never with an upstream library's bare exception text. Done once, in the
registry (``afmforce.io.load``), for every reader."""

from __future__ import annotations

import dataclasses

import pytest

import afmforce.io as io
from afmforce.errors import FileFormatError, MissingMetadataError
from afmforce.io import load


def _spm(tmp_path):
    path = tmp_path / "curve.spm"
    path.write_bytes(b"\\*Force file list\r\n\\*File list end\r\n")
    return path


@pytest.fixture
def raising_reader(monkeypatch):
    """The NanoScope reader replaced by one that raises what third-party parsers raise."""
    def use(exc):
        def loader(path, **kwargs):
            raise exc
        monkeypatch.setitem(io.FORMATS, "bruker-nanoscope",
                            dataclasses.replace(io.FORMATS["bruker-nanoscope"], loader=loader))
    return use


def test_missing_entry_names_reader_entry_and_meta(tmp_path, raising_reader):
    raising_reader(KeyError("Date"))
    with pytest.raises(FileFormatError) as err:
        load(_spm(tmp_path))
    msg = str(err.value)
    assert msg.startswith(f"{tmp_path / 'curve.spm'}: the Bruker NanoScope binary force file (v5-v9) reader "
                          "('bruker-nanoscope', detected from the content, via afmforce) could not read it")
    assert "the file lacks the entry 'Date'" in msg
    assert "`meta_override` KEY=VALUE" in msg and "spring_constant" in msg and "--" not in msg  # key; the CLI: --meta
    assert "report it" in msg and "KeyError: 'Date'" not in msg


def test_layout_error_and_chosen_reader(tmp_path, raising_reader):
    raising_reader(ValueError("buffer size must be a multiple of element size"))
    with pytest.raises(FileFormatError) as err:
        load(_spm(tmp_path), format="bruker-nanoscope")
    msg = str(err.value)
    assert "('bruker-nanoscope', chosen with format" in msg
    assert "not laid out as the reader expects (ValueError: buffer size" in msg
    assert "meta_override" not in msg  # nothing is missing: no metadata to give


def test_a_readers_own_refusal_names_it_and_the_other_readers(tmp_path):
    path = tmp_path / "curve.csv"
    path.write_text("Force-Distance Curve\nfoo,bar\n1,2\n")  # AFM Workshop's first line, nothing after
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "(reader 'afm-workshop-csv', detected from the content" in msg
    assert "named as `format`" in msg and "'bruker-ascii'" in msg  # the other reader of .csv (key, no flag)


def test_unrecognised_content_says_how_to_name_a_reader(tmp_path):
    path = tmp_path / "curve.txt"
    path.write_text("nothing a force file would hold\n")
    with pytest.raises(FileFormatError, match=r"not recognised as any of: .*as `format` \(one of .*bruker-ascii"):
        load(path)


def test_missing_metadata_is_left_as_the_reader_says_it(tmp_path):
    """A MissingMetadataError already names what to give: it passes unchanged."""
    path = tmp_path / "gel.txt"
    path.write_text("1,0\t2,0\t3,0\n" * 20)  # NT-MDT: three numeric columns, no k or InvOLS
    with pytest.raises(MissingMetadataError) as err:
        load(path, require=("spring_constant", "sensitivity"))
    assert "(reader " not in str(err.value) and "give `spring_constant` and `sensitivity`" in str(err.value)
