"""The project's environment variables (wgpuviewer.core.env): one parser each, the same answer from every command,
bad values as one line naming the variable, the value and the fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from maptools import cache
from maptools import cli as maptools_cli
from wgpuviewer import cli
from wgpuviewer.core import env, gpu
from wgpuviewer.core.errors import UserError
from wgpuviewer.viewer import settings


@pytest.mark.parametrize("text,size", [("0", 0), ("123", 123), ("500M", 500 * 2**20), ("2g", 2 * 2**30),
                                       ("1.5T", int(1.5 * 2**40)), ("2GiB", 2 * 2**30), (" 64 KB ", 64 * 2**10)])
def test_sizes(text, size):
    assert env.parse_bytes(text) == size


@pytest.mark.parametrize("variable,value,expected", [
    (env.CACHE_MAX, "-1", "expected a size such as 500M, 2G or 0 (no cap)"),
    (env.CACHE_MAX, "abc", "expected a size"),
    (env.CACHE_MAX, "0.5", "less than one byte"),  # would round to 0, which turns the cap off
    (env.BACKEND, "vulcan", "expected one of auto, vulkan, metal, dx12, gl"),
])
def test_a_bad_value_names_the_variable_the_value_and_the_fix(monkeypatch, variable, value, expected):
    monkeypatch.setenv(variable.name, value)
    with pytest.raises(UserError) as error:
        variable.value()
    message = str(error.value)
    assert message.startswith(f"${variable.name} = {value!r}: {expected}") and "\n" not in message
    assert f"set a valid value or unset it (default: {variable.default_text})" in message


def test_unset_and_empty_mean_the_default_and_paths_expand_the_home_folder(monkeypatch):
    monkeypatch.delenv(env.WGPU_BACKEND.name, raising=False)
    for variable in env.VARIABLES:
        monkeypatch.delenv(variable.name, raising=False)
        assert variable.value() == variable.default
        monkeypatch.setenv(variable.name, "  ")
        assert variable.value() == variable.default
    monkeypatch.setenv("HOME", "/home/someone")
    monkeypatch.setenv(env.CONFIG_DIR.name, "~/conf")
    assert settings.config_dir() == Path("/home/someone/conf")
    monkeypatch.setenv(env.CACHE_DIR.name, "~/maps")
    assert cache.cache_dir() == Path("/home/someone/maps")
    monkeypatch.setenv(env.BACKEND.name, " Vulkan ")
    assert gpu.resolve_backend(None) == "vulkan" and gpu.resolve_backend("gl") == "gl"


@pytest.mark.parametrize("value,backend", [("Vulkan", "vulkan"), ("Metal", "metal"), ("D3D12", "dx12"),
                                           ("OpenGL", "gl"), ("OpenGLES", "gl"), ("Undefined", "auto"),
                                           (" vulkan ", "vulkan")])
def test_wgpu_pys_variable_chooses_the_backend_when_ours_is_unset(monkeypatch, value, backend):
    monkeypatch.delenv(env.BACKEND.name, raising=False)
    monkeypatch.setenv(env.WGPU_BACKEND.name, value)
    assert env.BACKEND.value() == backend == gpu.resolve_backend(None)
    assert gpu.resolve_backend("gl") == "gl"  # --backend wins over both


@pytest.mark.parametrize("value", ["Null", "WebGPU", "D3D11", "vulcan"])
def test_a_wgpu_backend_we_do_not_run_on_is_refused_naming_wgpu_pys_variable(monkeypatch, value):
    monkeypatch.delenv(env.BACKEND.name, raising=False)
    monkeypatch.setenv(env.WGPU_BACKEND.name, value)
    with pytest.raises(UserError) as error:
        env.check_environment()
    assert str(error.value).startswith(f"$WGPU_BACKEND_TYPE = {value!r}: expected one of Undefined, Vulkan, Metal, "
                                       "D3D12, OpenGL, OpenGLES")


def test_ours_wins_over_wgpu_pys_and_says_so_once_where_they_disagree(monkeypatch, caplog):
    monkeypatch.setattr(env, "_NOTED", set())
    monkeypatch.setenv(env.BACKEND.name, "gl")
    for theirs, noted in (("OpenGL", False), ("Vulkan", True), ("Null", True)):  # a bad value of theirs: ignored
        monkeypatch.setenv(env.WGPU_BACKEND.name, theirs)
        caplog.clear()
        for _ in range(3):
            assert env.BACKEND.value() == "gl"
            env.check_environment()
        lines = [r.getMessage() for r in caplog.records if r.name == "wgpuviewer.env"]
        assert lines == ([f"$WGPUVIEWER_BACKEND = 'gl' wins over $WGPU_BACKEND_TYPE = {theirs!r}; unset one of "
                          "them to silence this"] if noted else []), theirs


def test_the_cli_prints_the_notice_as_one_warning_line(monkeypatch, capsys):
    monkeypatch.setattr(env, "_NOTED", set())
    monkeypatch.setenv(env.BACKEND.name, "vulkan")
    monkeypatch.setenv(env.WGPU_BACKEND.name, "Metal")
    assert cli.main(["techniques"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["wgpuviewer: warning: $WGPUVIEWER_BACKEND = 'vulkan' wins over $WGPU_BACKEND_TYPE = 'Metal'; "
                   "unset one of them to silence this"]


def test_the_backend_names_are_the_gpu_modules():
    assert env.BACKEND_CHOICES == gpu.BACKEND_CHOICES


@pytest.mark.parametrize("name,value", [("WGPUVIEWER_CACHE_MAX", "-1"), ("WGPUVIEWER_CACHE_MAX", "abc"),
                                        ("WGPUVIEWER_BACKEND", "vulcan"), ("WGPU_BACKEND_TYPE", "Null")])
def test_every_command_refuses_a_bad_variable_before_it_runs(tmp_path, monkeypatch, capsys, name, value):
    """`render` used to accept a bad cache cap whenever it built no map (and `cache info` refused it)."""
    monkeypatch.delenv(env.BACKEND.name, raising=False)
    monkeypatch.setenv(name, value)
    out = tmp_path / "x.png"
    for prog, run, argv in (("wgpuviewer", cli.main, ["render", "-o", str(out), "--size", "16x16",
                                                      "--technique", "basic"]),
                            ("wgpuviewer", cli.main, ["techniques"]),
                            ("maptools", maptools_cli.main, ["cache", "info"]),
                            ("maptools", maptools_cli.main, ["kinds"])):
        assert run(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"{prog}: error: ${name} = {value!r}: "), err
        assert "set a valid value or unset it" in err[0]
    assert not out.exists()
