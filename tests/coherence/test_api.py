"""The package's public names, imported on first use; the CLI module stays cheap to import."""

from __future__ import annotations

import subprocess
import sys

import pytest

import refnpr.coherence as coherence


def test_every_public_name_resolves():
    assert set(coherence.__all__) == set(coherence._EXPORTS)
    for name in coherence.__all__:
        assert getattr(coherence, name) is not None, name
    assert set(coherence.__all__) <= set(dir(coherence))


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match=r"has no attribute 'nope'"):
        coherence.nope  # noqa: B018


def test_cli_module_does_not_import_the_renderer():
    code = "import sys, refnpr.coherence.cli; print('refnpr.render' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_depth_rtol_default_matches_the_cli_help(capsys):
    from refnpr.cli import main

    with pytest.raises(SystemExit):
        main(["coherence", "--help"])
    assert "default 0.01, DEPTH_RTOL" in " ".join(capsys.readouterr().out.split())
    assert coherence.DEPTH_RTOL == 0.01


def test_function_names_are_not_shadowed_by_submodules():
    import importlib

    for name in coherence.__all__:
        importlib.import_module(f"refnpr.coherence.{coherence._EXPORTS[name]}")
    assert callable(coherence.warp) and callable(coherence.measure)
    assert not any(isinstance(getattr(coherence, n), type(coherence)) for n in coherence.__all__)
