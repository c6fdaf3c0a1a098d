"""The public API: `from lasa import *` works, and every exported name resolves."""

import subprocess
import sys

import lasa


def test_star_import_works_in_a_fresh_interpreter():
    code = "from lasa import *; print(Controller.__name__, publish.__name__, DemoConfig.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["Controller", "publish", "DemoConfig"]


def test_all_and_the_lazy_table_agree():
    assert sorted(lasa.__all__) == sorted(lasa._EXPORTS)
    for name in lasa.__all__:
        assert getattr(lasa, name) is not None


def test_unknown_name_is_an_attribute_error():
    import pytest

    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        lasa.nope  # noqa: B018
