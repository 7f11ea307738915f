"""Viewer settings: platform paths, round trip, atomic writes, and bad files that must not crash."""

from __future__ import annotations

from pathlib import Path

import pytest

from wgpuviewer.viewer import settings as st
from wgpuviewer.viewer.settings import Settings, load_settings, save_settings


@pytest.fixture
def config(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv(st.CONFIG_ENV, str(tmp_path))
    return tmp_path / st.FILE_NAME


def test_config_dir_per_platform(monkeypatch, tmp_path):
    monkeypatch.delenv(st.CONFIG_ENV, raising=False)
    monkeypatch.setattr(st.Path, "home", classmethod(lambda cls: Path("/home/u")))
    monkeypatch.setattr(st.sys, "platform", "linux")
    monkeypatch.delenv("XDG_CONFIG_HOME", raising=False)
    assert st.config_dir() == Path("/home/u/.config/wgpuviewer")
    monkeypatch.setenv("XDG_CONFIG_HOME", "/xdg")
    assert st.config_dir() == Path("/xdg/wgpuviewer")
    monkeypatch.setenv("XDG_CONFIG_HOME", "relative")  # the XDG spec says: ignore relative paths
    assert st.config_dir() == Path("/home/u/.config/wgpuviewer")
    monkeypatch.setattr(st.sys, "platform", "darwin")
    assert st.config_dir() == Path("/home/u/Library/Application Support/wgpuviewer")
    monkeypatch.setattr(st.sys, "platform", "win32")
    monkeypatch.setenv("APPDATA", "C:/Users/u/AppData/Roaming")
    assert st.config_dir() == Path("C:/Users/u/AppData/Roaming/wgpuviewer")
    monkeypatch.setenv(st.CONFIG_ENV, str(tmp_path))
    assert st.config_dir() == tmp_path and st.settings_path() == tmp_path / "settings.toml"


def test_missing_file_gives_defaults_silently(config):
    assert load_settings() == (Settings(), [])


def test_round_trip_and_atomic_write(config):
    wanted = Settings(width=800, height=600, fullscreen=True, vsync=False, camera_mode="orbit", move_speed=3.25,
                      look_sensitivity=0.002, last_scene='C:\\scenes\\"odd" name.toml', last_technique="pom",
                      render_scale="0.5")
    assert save_settings(wanted) == config
    assert load_settings() == (wanted, [])
    assert [p.name for p in config.parent.iterdir()] == ["settings.toml"]  # no temporary file left behind
    save_settings(Settings())  # replaced, not appended
    assert load_settings() == (Settings(), [])


@pytest.mark.parametrize(
    "text, warning",
    [
        ("width = = 3\n", "corrupt"),
        ("\x00\xff garbage", "corrupt"),
        ("version = 0\nwidth = 800\n", "settings version 0"),
        ("width = 800\n", "settings version None"),
    ],
)
def test_corrupt_or_outdated_file_gives_defaults_and_a_warning(config, text, warning, caplog):
    config.write_text(text, encoding="utf-8", errors="surrogateescape")
    settings, warnings = load_settings()
    assert settings == Settings()
    assert len(warnings) == 1 and warning in warnings[0] and "default" in warnings[0]
    assert warning in caplog.text


def test_bad_values_fall_back_one_by_one(config):
    config.write_text(
        f"version = {st.VERSION}\nwidth = 800\nheight = -5\nvsync = 'yes'\ncamera_mode = 'spin'\n"
        "move_speed = nan\nlook_sensitivity = 0.01\nshiny = true\nrender_scale = '0.6'\n"
    )
    settings, warnings = load_settings()
    assert settings == Settings(width=800, look_sensitivity=0.01)
    assert len(warnings) == 6
    assert any("render_scale = '0.6': expected one of auto, 1, 0.75" in w for w in warnings)
    assert any("height = -5: out of range" in w for w in warnings)
    assert any("unknown setting 'shiny'" in w for w in warnings)


def test_unreadable_file_is_survived(config):
    config.mkdir()  # a directory where the file should be
    settings, warnings = load_settings()
    assert settings == Settings() and "unreadable" in warnings[0]
