"""The claims table: merge by key, Markdown twin, verdict validation."""

import pandas as pd
import pytest

from lasa.claims import CLAIM_COLUMNS, Claim, update_claims
from lasa.errors import ConfigError


def claim(text, figure="sim1", robot="planar5", verdict="yes"):
    return Claim(
        claim=text, figure=figure, paper="p", measured="m", reproduced=verdict, note="n", robot=robot
    )


def test_update_replaces_own_rows_and_keeps_others(tmp_path):
    path = tmp_path / "claims.csv"
    update_claims(path, [claim("a"), claim("b")])
    update_claims(path, [claim("x", figure="sim2")])
    table = update_claims(path, [claim("a", verdict="no")])
    assert list(table.columns) == list(CLAIM_COLUMNS)
    assert len(table) == 3
    assert table.set_index("claim").loc["a", "reproduced"] == "no"
    on_disk = pd.read_csv(path)
    assert len(on_disk) == 3
    md = path.with_suffix(".md").read_text()
    assert md.startswith("| claim | figure |") and md.count("\n") == 5


def test_pipes_in_text_are_escaped(tmp_path):
    update_claims(tmp_path / "c.csv", [claim("a | b")])
    assert "a \\| b" in (tmp_path / "c.md").read_text()


def test_bad_verdict_is_refused():
    with pytest.raises(ConfigError, match="reproduced"):
        claim("a", verdict="maybe")


def test_foreign_file_is_refused(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text("a,b\n1,2\n")
    with pytest.raises(ConfigError, match="lacks columns"):
        update_claims(path, [claim("a")])
