"""`afmforce.web.Settings` as Python users write it (audit: `Settings(data="folder")` made
`create_app` fail with AttributeError: 'str' object has no attribute 'mkdir')."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi")

from afmforce.web import Settings, create_app  # noqa: E402


def test_a_data_folder_given_as_text_is_a_path(tmp_path):
    folder = tmp_path / "serve-data"
    s = Settings(data=str(folder), spare_job=False)
    assert s.data == folder
    create_app(s)
    assert folder.is_dir()
