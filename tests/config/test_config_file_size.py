"""A config file is read up to ``MAX_CONFIG_BYTES``: a larger one is refused, naming it, before
it is read whole (32 features with a list of 10**6 values each parsed to gigabytes)."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import ConfigError
from gaitpref.config import load_config
from gaitpref.config import parse as parse_module

TEXT = """
[space.step_length]
min = 0.08
max = 0.18
num = 11
[model]
lengthscale = 0.05
signal_variance = 1.0
noise = 0.05
"""


def test_a_file_past_the_limit_is_refused_naming_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "big.toml"
    path.write_text(TEXT, "utf-8")
    size = path.stat().st_size
    monkeypatch.setattr(parse_module, "MAX_CONFIG_BYTES", size - 1)
    with pytest.raises(ConfigError, match=rf"'{path}' is larger than the {size - 1:,} bytes"):
        load_config(path)
    monkeypatch.setattr(parse_module, "MAX_CONFIG_BYTES", size)
    assert len(load_config(path).space) == 11


def test_line_endings_are_read_as_before(tmp_path: Path) -> None:
    """Read as bytes now, the text is the one ``read_text`` gave: the stored config (and its
    hash) of a file with Windows line endings is unchanged."""
    unix, windows = tmp_path / "unix.toml", tmp_path / "windows.toml"
    unix.write_bytes(TEXT.encode())
    windows.write_bytes(TEXT.replace("\n", "\r\n").encode())
    assert load_config(windows).text == load_config(unix).text == windows.read_text("utf-8")
