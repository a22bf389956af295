"""model.json has one writer, the model card: what a model directory holds reads into a card
and writes back byte for byte, and an entry given as a typed value is written as that value
says its JSON."""

import json
from pathlib import Path

import pytest

from models.card import StartReference
from models.store import load_model, write_model

SHIPPED = sorted(p.parent for p in (Path(__file__).resolve().parents[1] / "models").glob(
    "*/model.json"))


@pytest.mark.parametrize("directory", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_model_reads_and_writes_back_byte_for_byte(directory, tmp_path):
    model = load_model(directory)
    assert model.card.to_document() == json.loads((directory / "model.json").read_text())
    write_model(model, tmp_path / "copy")
    assert (tmp_path / "copy" / "model.json").read_bytes() == \
        (directory / "model.json").read_bytes()
    assert (tmp_path / "copy" / "weights.npz").read_bytes() == \
        (directory / "weights.npz").read_bytes()


def test_a_typed_entry_is_written_as_it_says_and_read_back_as_the_same_value(tmp_path):
    shipped = load_model()
    write_model(shipped, tmp_path / "m")
    model = load_model(tmp_path / "m")
    start = StartReference(reference=(0.01, -0.02), thresholds=(0.5, None), spread=(0.1, 0.2),
                           span_s=2.0, logs=3, heldout_logs=1)
    untouched = model.with_entries(start_state=start)
    assert untouched.card.start_state == start and model.card.start_state != start
    assert not model.unsaved
    model.update_entries(start_state=start)
    assert model.unsaved and model.card.start_state == start
    write_model(model, tmp_path / "m")
    assert not model.unsaved
    written = json.loads((tmp_path / "m" / "model.json").read_text())
    assert written["start_state"] == start.to_json()
    assert load_model(tmp_path / "m").card.start_state == start
    # everything else is as it was
    assert {k: v for k, v in written.items() if k != "start_state"} == \
        {k: v for k, v in shipped.card.to_document().items() if k != "start_state"}
