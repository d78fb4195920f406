"""The one bounded JSON reader (issue 41, finding 8): the size is checked before a byte is
parsed (a 200 MB diagnosis.json grew to 22.9 GB in 0.5.0), the nesting is counted in chunks
(0.5.0's count took eight bytes a character, several times over), NaN and Infinity are
refused; every reader of a user's JSON file goes through it."""

from __future__ import annotations

import json
import tracemalloc

import pytest

from zrp.errors import InputError
from zrp.jsonio import (
    MAX_COMPENSATION_BYTES,
    MAX_DIAGNOSIS_BYTES,
    MAX_JSON_DEPTH,
    json_depth,
    loads_json,
    read_json,
)


def _big(path, size: int) -> None:
    with open(path, "wb") as fh:  # a sparse file: nothing is written, the size is what counts
        fh.truncate(size)


@pytest.mark.parametrize("limit, what", [(MAX_DIAGNOSIS_BYTES, "diagnosis.json"),
                                         (MAX_COMPENSATION_BYTES, "compensation file")])
def test_a_file_over_the_limit_is_refused_before_it_is_read(tmp_path, limit, what):
    _big(tmp_path / "f.json", limit + 1)
    with pytest.raises(InputError, match=rf"more than the .*at most {limit // 2**20} MiB"):
        read_json(tmp_path / "f.json", max_bytes=limit, what=what)


def test_the_stored_diagnosis_and_compensation_readers_use_the_limits(tmp_path):
    from zrp.calibration import read_calibration
    from zrp.calibration.recipe import stored_record
    from zrp.gap.results import load_diagnosis

    _big(tmp_path / "diagnosis.json", MAX_DIAGNOSIS_BYTES + 1)
    _big(tmp_path / "compensation.json", MAX_COMPENSATION_BYTES + 1)
    for read in (stored_record, load_diagnosis):
        with pytest.raises(InputError, match="50 MiB"):
            read(tmp_path / "diagnosis.json")
    with pytest.raises(InputError, match="20 MiB"):
        read_calibration(tmp_path / "compensation.json")


def test_depth_is_counted_outside_strings():
    assert json_depth('{"a": "[[[[", "b": [{}], "c": "\\"[["}') == 3
    assert json_depth("[" * 40 + "]" * 40) == 40
    with pytest.raises(InputError, match=f"nested 40 deep.*at most {MAX_JSON_DEPTH}"):
        loads_json("[" * 40 + "]" * 40, "f.json")


def test_depth_counting_takes_memory_of_the_order_of_the_text():
    text = json.dumps([[i, "x[y", {"k": [1.5, 2.5]}] for i in range(300_000)])
    tracemalloc.start()
    try:
        assert json_depth(text) == 4
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # 0.5.0: np.isin over the whole text and int64 steps, ~30 bytes a character
    assert peak < 8 * len(text)


@pytest.mark.parametrize("word", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_constants_are_refused(word):
    with pytest.raises(InputError, match=f"{word} is not a JSON number"):
        loads_json(f'{{"x": {word}}}', "f.json")
