"""A sweep file's tables and ``[sweep]`` options are checked as they are read: a wrong type is one
ParameterError naming the table and key (before: KeyError 'lo', OverflowError, ValueError, i.e.
"unexpected ... a bug" on the command line), never a silently truncated number."""

from __future__ import annotations

import pytest

from afmforce.errors import ParameterError
from afmforce.sweep.spec import build_spec, chunk_size_from_config

BAD = {
    "[grid]\n[grid.xi]\na = 1\n": "[grid] xi must be a table { lo = ..., hi = ..., n = ..., log = true }",
    "[grid]\nxi = { lo = 0.001, n = 3 }\n": "[grid] xi must be a table",
    "[grid]\nxi = { lo = 0.001, hi = 0.1, n = 2.5 }\n": "n must be a whole number, got 2.5",
    "[grid]\nxi = { lo = 0.001, hi = 0.1, n = 3, log = \"yes\" }\n": "log must be true or false",
    "[range]\nxi = { lo = 0.001, hi = 0.1, n = 3 }\n": "[range] xi must be a table { lo = ..., hi = ..., log = true }",
    "[grid]\nxi = \"0.001:0.1:3\"\n[sweep]\nn = 1e400\n": "[sweep] n (the number of samples) must be a whole number >= 0, got inf",
    "[grid]\nxi = \"0.001:0.1:3\"\n[sweep]\nn = 4.7\n": "got 4.7",
    "[grid]\nxi = \"0.001:0.1:3\"\n[sweep]\nseed = \"x\"\n": "[sweep] seed (the sampler's seed) must be a whole number",
    "[grid]\nxi = \"0.001:0.1:3\"\n[sweep]\nsample = 5\n": "[sweep] sample must be the sampler, 'random' or 'lhs'",
    "[grid]\nxi = \"0.001:0.1:3\"\n[sweep]\nworkers = 4\n": "unknown [sweep] option(s) ['workers']",
    "grid = 5\n": "grid must be a table ([grid]), got 5",
}


@pytest.mark.parametrize("text", list(BAD))
def test_a_malformed_sweep_file_is_one_parameter_error(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError) as err:
        build_spec(config=path)
    assert BAD[text] in str(err.value)


def test_the_documented_inline_tables_still_read(tmp_path):
    """docs/sweep.md's file: xi = { lo = 0.001, hi = 0.1, n = 5, log = true } -> 5 log-spaced values."""
    path = tmp_path / "s.toml"
    path.write_text('[sweep]\nchunk_size = 10\nsample = "lhs"\nn = 4\nseed = 1\n[grid]\n'
                    'xi = { lo = 0.001, hi = 0.1, n = 5, log = true }\n[range]\nradius = { lo = 5e-8, hi = 2.5e-7 }\n',
                    encoding="utf-8")
    spec = build_spec(config=path)
    assert spec.grid[0].values == pytest.approx([1e-3, 10 ** -2.5, 1e-2, 10 ** -1.5, 1e-1], rel=1e-12)
    assert (spec.n, spec.seed, spec.sample) == (4, 1, "lhs")
    assert (spec.ranges[0].lo, spec.ranges[0].hi, spec.ranges[0].log) == (5e-8, 2.5e-7, False)
    assert chunk_size_from_config(path) == 10


def test_a_zero_chunk_size_in_the_file_is_refused(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[grid]\nxi = "0.001:0.1:3"\n[sweep]\nchunk_size = 0\n', encoding="utf-8")
    with pytest.raises(ParameterError, match="chunk_size must be at least 1, got 0"):
        chunk_size_from_config(path)


def test_the_cli_says_one_error_line_without_a_traceback(tmp_path, capsys):
    from afmforce.cli.main import main

    path = tmp_path / "s.toml"
    path.write_text("[grid]\n[grid.xi]\na = 1\n", encoding="utf-8")
    code = main(["sweep", "--config", str(path), "--serial", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.strip().count("\n") == 0 and err.startswith("error: --config ")
    assert "Traceback" not in err and "unexpected" not in err
    assert not (tmp_path / "out").exists()
