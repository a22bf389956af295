"""Protocol Buffers in MCAP (message and schema encoding "protobuf"), as vehicles without ROS
log through Foxglove's tools: read without the protobuf runtime, checked against it."""

import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from adapters import read_log
from adapters.protobuf_decode import decoder
from adapters.protobuf_schema import SchemaError, message_types
from adapters.protobuf_wire import WireError
from auvdiag_cli.cli import app
from auvdiag_cli.fuzz.mutations import mutate
from auvdiag_cli.simulator.writers.protobuf import varint
from auvdiag_cli.vehicle.profile import load_profile

pb = pytest.importorskip("google.protobuf", reason="the protobuf library checks the reader")
from google.protobuf import (  # noqa: E402
    descriptor_pb2,
    descriptor_pool,
    message_factory,
)

runner = CliRunner()
F = descriptor_pb2.FieldDescriptorProto
MESSAGES = 300
UNSET_DEPTH = {k for k in range(MESSAGES) if k % 50 == 7}


def _vehicle_file() -> descriptor_pb2.FileDescriptorProto:
    """A proto3 file of every kind of field a vehicle's state may use: packed floats, a
    nested message, a proto3 `optional`, an enum, zigzag and negative integers, a map,
    fixed-size integers, a string and a flag."""
    file = descriptor_pb2.FileDescriptorProto(name="vehicle.proto", package="vehicle",
                                              syntax="proto3")
    vector = file.message_type.add(name="Vector3")
    for number, name in enumerate("xyz", 1):
        vector.field.add(name=name, number=number, type=F.TYPE_DOUBLE, label=F.LABEL_OPTIONAL)
    state = file.message_type.add(name="State")
    state.enum_type.add(name="Mode").value.add(name="IDLE", number=0)
    state.enum_type[0].value.add(name="DIVE", number=1)
    entry = state.nested_type.add(name="GainsEntry")
    entry.options.map_entry = True
    entry.field.add(name="key", number=1, type=F.TYPE_STRING, label=F.LABEL_OPTIONAL)
    entry.field.add(name="value", number=2, type=F.TYPE_DOUBLE, label=F.LABEL_OPTIONAL)
    state.oneof_decl.add(name="_depth")
    fields = [("stamp_ns", F.TYPE_UINT64, ""), ("thrust", F.TYPE_FLOAT, ""),
              ("rate", F.TYPE_MESSAGE, ".vehicle.Vector3"), ("depth", F.TYPE_DOUBLE, ""),
              ("mode", F.TYPE_ENUM, ".vehicle.State.Mode"), ("trim", F.TYPE_SINT32, ""),
              ("offset", F.TYPE_INT32, ""), ("gains", F.TYPE_MESSAGE, ".vehicle.State.GainsEntry"),
              ("note", F.TYPE_STRING, ""), ("count", F.TYPE_FIXED32, ""),
              ("heading", F.TYPE_SFIXED64, ""), ("ok", F.TYPE_BOOL, "")]
    for number, (name, kind, type_name) in enumerate(fields, 1):
        repeated = name in ("thrust", "gains")
        field = state.field.add(name=name, number=number, type=kind,
                                label=F.LABEL_REPEATED if repeated else F.LABEL_OPTIONAL)
        if type_name:
            field.type_name = type_name
        if name == "depth":
            field.oneof_index, field.proto3_optional = 0, True
    return file


def _state_class(file: descriptor_pb2.FileDescriptorProto) -> type:
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("vehicle.State"))


def _states() -> list[bytes]:
    state = _state_class(_vehicle_file())
    messages = []
    for k in range(MESSAGES):
        message = state(stamp_ns=1_700_000_000_000_000_000 + k, thrust=[
            math.sin(k / 20), math.cos(k / 30), -0.5], mode=k % 2, trim=-k, offset=-3 * k,
            note="ok", count=k, heading=-1000 * k, ok=k % 2 == 0)
        message.rate.z = k / 100
        message.gains["roll"], message.gains["yaw"] = 1.5, float(k)
        if k not in UNSET_DEPTH:
            message.depth = k / 10
        messages.append(message.SerializeToString())
    return messages


def _descriptor_set(file: descriptor_pb2.FileDescriptorProto) -> bytes:
    return descriptor_pb2.FileDescriptorSet(file=[file]).SerializeToString()


def _state_mcap(path: Path, type_name: str = "vehicle.State",
                messages: list[bytes] | None = None, encoding: str = "protobuf") -> Path:
    from mcap.writer import Writer

    with path.open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile="", library="test")
        schema = writer.register_schema(type_name, encoding, _descriptor_set(_vehicle_file()))
        channel = writer.register_channel("/state", "protobuf", schema)
        for k, data in enumerate(messages or _states()):
            time_ns = 1_700_000_000_000_000_000 + k * 100_000_000
            writer.add_message(channel, log_time=time_ns, publish_time=time_ns, data=data)
        writer.finish()
    return path


def test_the_reader_decodes_what_the_library_wrote():
    decode = decoder(message_types(_descriptor_set(_vehicle_file())), "vehicle.State")
    state = _state_class(_vehicle_file())
    for data in _states():
        real, ours = state.FromString(data), decode(data)
        assert ours["thrust"] == list(real.thrust) and ours["rate"]["z"] == real.rate.z
        assert ours["depth"] == (real.depth if real.HasField("depth") else None)
        assert ours["gains"] == dict(real.gains) and ours["note"] == "ok"
        assert (ours["stamp_ns"], ours["mode"], ours["trim"], ours["offset"], ours["count"],
                ours["heading"], ours["ok"]) == (real.stamp_ns, real.mode, real.trim,
                                                 real.offset, real.count, real.heading, real.ok)
    assert decode(b"")["rate"] is None and decode(b"")["trim"] == 0   # proto3's defaults


def test_inspect_lists_the_fields_and_a_draft_reads_them(tmp_path):
    """`inspect` lists the fields from the schema; `init-profile` drafts a profile that reads
    them; a proto3 `optional` left unset is no reading at that time."""
    log = _state_mcap(tmp_path / "state.mcap")
    shown = runner.invoke(app, ["inspect", str(log)])
    assert shown.exit_code == 0, shown.output
    assert "vehicle.State" in shown.output
    listed = " ".join(shown.output.split())
    assert "stamp_ns, thrust[0], rate.x, rate.y, rate.z, depth, mode, trim, offset" in listed
    draft = tmp_path / "draft.toml"
    drafted = runner.invoke(app, ["init-profile", str(log), "--output", str(draft)])
    assert drafted.exit_code == 0, drafted.output
    checked = runner.invoke(app, ["inspect", str(log), "--profile", str(draft)])
    assert checked.exit_code == 0 and "MISSING" not in checked.output, checked.output
    text = draft.read_text()
    assert 'thrust_0 = { topic = "/state", field = "thrust[0]" }' in text, text
    signals = read_log(log, load_profile(draft).sources).series
    assert signals["thrust_0"].values[20] == pytest.approx(math.sin(1.0))
    depth = signals["depth"]
    assert len(depth) == MESSAGES - len(UNSET_DEPTH)
    assert depth.values[-1] == pytest.approx((MESSAGES - 1) / 10)


def test_every_simulated_message_reads_as_the_library_reads_it(make_log):
    """What `simulate --format protobuf-mcap` writes is Protocol Buffers: the library loads
    each channel's FileDescriptorSet and parses every message to the same values."""
    from google.protobuf.json_format import MessageToDict
    from mcap.reader import make_reader

    classes: dict[int, tuple[type, object]] = {}
    with make_log("paper-normal", 11, "protobuf-mcap").open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages():
            if schema.id not in classes:
                pool = descriptor_pool.DescriptorPool()
                for file in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
                    pool.Add(file)
                classes[schema.id] = (message_factory.GetMessageClass(
                    pool.FindMessageTypeByName(schema.name)),
                    decoder(message_types(schema.data), schema.name))
            real, ours = classes[schema.id]
            expected = MessageToDict(real.FromString(message.data),  # type: ignore[attr-defined]
                                     preserving_proto_field_name=True,
                                     always_print_fields_with_no_presence=True)
            assert _as_json(ours(message.data)) == _as_json(expected), channel.topic
    assert len(classes) >= 3


def _as_json(value: object) -> object:
    """Values as the library's JSON mapping gives them (64-bit integers as strings)."""
    if isinstance(value, dict):
        return {k: _as_json(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_as_json(v) for v in value]
    if isinstance(value, str) and value.lstrip("-").isdigit():
        return int(value)
    return value


@pytest.mark.parametrize(("type_name", "encoding", "problem"), [
    ("vehicle.Missing", "protobuf", "its FileDescriptorSet has no message type "
                                    "'vehicle.Missing'"),
    ("vehicle.State", "", "its Protocol Buffers messages come without their "
                          "FileDescriptorSet")])
def test_a_schema_that_does_not_say_what_the_messages_hold_is_one_line(tmp_path, type_name,
                                                                       encoding, problem):
    log = _state_mcap(tmp_path / "state.mcap", type_name=type_name, encoding=encoding)
    result = runner.invoke(app, ["diagnose", str(log), "--profile",
                                 str(_state_profile(tmp_path))])
    assert result.exit_code == 2
    assert f"state.mcap: cannot decode /state: {problem}" in result.output
    assert len(result.output.strip().splitlines()) == 1, result.output


def test_a_damaged_message_ends_the_read_there(tmp_path):
    messages = _states()
    messages[100] = messages[100][:-3]            # cut inside its last field
    log = _state_mcap(tmp_path / "state.mcap", messages=messages)
    signals = read_log(log, load_profile(_state_profile(tmp_path)).sources)
    assert len(signals.series["flow"]) == 100
    assert any("log damaged" in note for note in signals.notes), signals.notes


def _state_profile(folder: Path) -> Path:
    """The Twin-Burger profile reading its four signals from the state's fields."""
    from auvdiag_cli.vehicle.profile import profile_text

    text, _ = profile_text(None)
    start = text.index("[sources.ros.signals]\n") + len("[sources.ros.signals]\n")
    end = text.index("\n\n", start)
    mapped = {"thruster_0": "thrust[0]", "thruster_1": "thrust[1]", "flow": "rate.z",
              "yaw_rate": "rate.z"}
    path = folder / "state.toml"
    path.write_text(text[:start] + "\n".join(
        f'{name} = {{ topic = "/state", field = "{field}" }}' for name, field in mapped.items())
        + text[end:])
    return path


def test_damaged_bytes_raise_only_the_readers_own_errors():
    """Mutated messages and schemas: decoded, or refused as bytes that are no such message;
    a type that holds itself, fed bytes nested past any vehicle's, stops at a depth."""
    schema = _descriptor_set(_vehicle_file())
    messages = _states()
    def state_of(data: bytes, descriptor_set: bytes) -> None:
        decoder(message_types(descriptor_set), "vehicle.State")(data)

    outcomes = {"read": 0, "refused": 0}
    for seed in range(1500):
        for data, descriptor_set in ((mutate(messages[seed % MESSAGES], seed)[0], schema),
                                     (messages[0], mutate(schema, seed)[0])):
            try:
                state_of(data, descriptor_set)
                outcomes["read"] += 1
            except (WireError, SchemaError):
                outcomes["refused"] += 1
    assert min(outcomes.values()) > 100, outcomes
    node = descriptor_pb2.FileDescriptorProto(name="n.proto", package="n", syntax="proto3")
    node.message_type.add(name="Node").field.add(name="child", number=1, type=F.TYPE_MESSAGE,
                                                 type_name=".n.Node", label=F.LABEL_OPTIONAL)
    deep = b""
    for _ in range(500):
        deep = b"\x0a" + varint(len(deep)) + deep
    with pytest.raises(WireError, match="nested deeper"):
        decoder(message_types(_descriptor_set(node)), "n.Node")(deep)



def test_only_the_fields_read_are_decoded_and_a_missing_one_is_named(tmp_path):
    """A channel's decoder decodes only the fields the profile reads (to the same values);
    a field the type lacks is refused naming the fields it has."""
    from adapters.protobuf_decode import decoder as make_decoder
    from auvdiag_errors import LogError

    types = message_types(_descriptor_set(_vehicle_file()))
    full = make_decoder(types, "vehicle.State")
    pruned = make_decoder(types, "vehicle.State", ["rate.z", "thrust[1]", 'gains["yaw"]'])
    for data in _states()[:50]:
        whole, some = full(data), pruned(data)
        assert some == {"thrust": whole["thrust"], "rate": {"z": whole["rate"]["z"]},
                        "gains": whole["gains"]}
    profile = _state_profile(tmp_path)
    profile.write_text(profile.read_text().replace('"rate.z" }', '"rate.w" }', 1))
    with pytest.raises(LogError, match=r"has no field 'rate.w' \(signal flow\); its fields, "
                                       r"closest first: rate.x, rate.y, rate.z"):
        read_log(_state_mcap(tmp_path / "state.mcap"), load_profile(profile).sources)


def test_a_where_filter_reads_an_enum_by_its_number(tmp_path):
    profile = _state_profile(tmp_path)
    profile.write_text(profile.read_text().replace(
        'flow = { topic = "/state", field = "rate.z" }',
        'flow = { topic = "/state", field = "rate.z", where = { mode = "1" } }'))
    flow = read_log(_state_mcap(tmp_path / "state.mcap"), load_profile(profile).sources
                    ).series["flow"]
    assert len(flow) == MESSAGES // 2 and flow.values[0] == pytest.approx(0.01)
