"""hunt47c: loaders, Record construction, JSON files, CLI and docs as a newcomer meets them."""

from __future__ import annotations

import json

import numpy as np
import pytest

import graybox as gb


def _pareto_json(failures: dict) -> str:
    return json.dumps({"format": "graybox", "format_version": 1, "type": "ParetoSet",
                       "object": {"method": "pe", "structure": ["y(k-1)"], "lambdas": [], "thetas": [], "J1": [],
                                  "JS": [], "JSF": [], "extra": {}, "failures": failures}})


@pytest.mark.parametrize("key", ["--1", "\u00b2", "1\u00b2", "-"])
def test_failure_index_not_an_integer_is_a_file_error(key):
    # a hand-edited member index that str.isdigit takes (superscripts) or lstrip('-') hides ('--1') ended in
    # int()'s bare "invalid literal for int()", naming neither the file nor the field
    with pytest.raises(gb.GrayboxFileError, match=r"<json>: object\.failures\..*integer"):
        gb.from_json(_pareto_json({key: "x"}))
