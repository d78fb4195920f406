"""Dask is an optional extra (`pip install "zrp-accuracy[cluster]"`): without it the commands
run in this process as before, and --workers / --scheduler are a named error naming the extra,
before any work."""

from __future__ import annotations

import sys

import pytest

from zrp.cli import main
from zrp.cli.cluster import executor
from zrp.errors import InputError


@pytest.fixture
def no_dask(monkeypatch):
    for name in ("dask", "distributed"):  # an import of either now raises ImportError
        monkeypatch.setitem(sys.modules, name, None)


@pytest.mark.parametrize("kwargs, field", [({"workers": 2}, "--workers"),
                                           ({"scheduler": "tcp://127.0.0.1:1"}, "--scheduler")])
def test_a_cluster_without_dask_names_the_extra(no_dask, kwargs, field):
    with pytest.raises(InputError, match=r'zrp-accuracy\[cluster\]') as info, \
            executor(**kwargs):
        pass
    assert str(info.value).startswith(field)


def test_commands_without_a_cluster_do_not_need_dask(no_dask, tmp_path, capsys):
    assert main(["tolerance", "--robots", "100", "--steps", "20", "--no-progress"]) == 0
    assert main(["tolerance", "--robots", "100", "--steps", "20", "--no-progress",
                 "--workers", "2"]) == 2
    assert 'pip install "zrp-accuracy[cluster]"' in capsys.readouterr().err
