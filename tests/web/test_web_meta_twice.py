"""The web's ``meta`` overrides: a key given twice with different values is a 422 naming the field,
not the last value taken silently (as ``--meta``; tests/io/test_meta_args.py)."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi")


def test_web_refuses_two_values():
    from afmforce.web.validate import FieldError, metadata

    with pytest.raises(FieldError, match="given twice with different values"):
        metadata(["spring_constant=0.2", "velocity=1um/s", "spring_constant=0.3"])
    assert metadata(["spring_constant=0.2", "spring_constant=200mN/m"]) == {"spring_constant": 0.2}
