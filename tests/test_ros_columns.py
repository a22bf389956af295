"""Column-wise field reading from serialised ROS 1 and CDR messages, against rosbags'
own deserialisers on the same bytes: alignment, strings of every length, empty and
non-empty sequences, arrays of messages, indices."""

import numpy as np
import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from adapters.fieldpath import field_getter
from adapters.ros_columns import ColumnReader, NotColumnar, RawMessages

AWKWARD = """
uint8 small
float64 wide
string label
int16[] shorts
float32 single
bool flag
uint8[] bytes_maybe_empty
int64 big
"""
AWKWARD_TYPE = "test_msgs/msg/Awkward"


def store_for(encoding):
    store = get_typestore(Stores.ROS1_NOETIC if encoding == "ros1" else Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(AWKWARD, AWKWARD_TYPE))
    return store


def serialise(store, encoding, message, msgtype, little_endian=True):
    if encoding == "ros1":
        return store.serialize_ros1(message, msgtype)
    return store.serialize_cdr(message, msgtype, little_endian=little_endian)


def deserialise(store, encoding, raw, msgtype):
    if encoding == "ros1":
        return store.deserialize_ros1(raw, msgtype)
    return store.deserialize_cdr(raw, msgtype)


def messages_of(store, msgtype, rng, count=60):
    types = store.types
    out = []
    for i in range(count):
        if msgtype == AWKWARD_TYPE:
            out.append(store.types[AWKWARD_TYPE](
                small=i % 256, wide=float(rng.normal()), label="x" * (i % 7),
                shorts=rng.integers(-300, 300, 2 + i % 3).astype(np.int16),
                single=float(np.float32(rng.normal())), flag=bool(i % 2),
                bytes_maybe_empty=np.arange(i % 3, dtype=np.uint8), big=-(2**40) + i))
        elif msgtype == "std_msgs/msg/Float64MultiArray":
            dims = [types["std_msgs/msg/MultiArrayDimension"](label="d" * (j + i % 4),
                                                             size=j + 1, stride=i)
                    for j in range(1 + i % 3)]
            layout = types["std_msgs/msg/MultiArrayLayout"](dim=dims, data_offset=i)
            out.append(types[msgtype](layout=layout, data=rng.normal(size=2 + i % 5)))
        else:
            header_type = types["std_msgs/msg/Header"]
            stamp = types["builtin_interfaces/msg/Time"](sec=1000 + i, nanosec=7 * i)
            header = (header_type(seq=i, stamp=stamp, frame_id="imu" * (i % 4))
                      if "seq" in header_type.__dataclass_fields__
                      else header_type(stamp=stamp, frame_id="imu" * (i % 4)))
            vector = types["geometry_msgs/msg/Vector3"]
            out.append(types[msgtype](
                header=header,
                orientation=types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=rng.normal(size=9),
                angular_velocity=vector(x=float(i), y=0.5, z=float(rng.normal())),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vector(x=float(rng.normal()), y=0.0, z=9.8),
                linear_acceleration_covariance=np.zeros(9)))
    return out


PATHS = {
    AWKWARD_TYPE: ["small", "wide", "label", "shorts[1]", "single", "flag",
                   "big"],
    "std_msgs/msg/Float64MultiArray": ["layout.dim[0].size", "layout.dim[0].label",
                                       "layout.data_offset", "data[0]", "data[1]"],
    "sensor_msgs/msg/Imu": ["header.stamp.sec", "header.stamp.nanosec", "header.frame_id",
                            "orientation.w", "orientation_covariance[4]",
                            "angular_velocity.z", "linear_acceleration.x"],
}


@pytest.mark.parametrize("encoding", ["ros1", "cdr"])
@pytest.mark.parametrize("msgtype", sorted(PATHS))
def test_columns_equal_the_deserialised_fields(encoding, msgtype):
    store = store_for(encoding)
    batch = RawMessages(cdr=encoding == "cdr")
    originals = messages_of(store, msgtype, np.random.default_rng(2))
    for i, message in enumerate(originals):
        batch.append(i, serialise(store, encoding, message, msgtype))
    decoded = [deserialise(store, encoding, raw, msgtype) for raw in batch.messages()]
    reader = ColumnReader(batch, msgtype, store)
    for path in PATHS[msgtype]:
        expected = [field_getter(path)(m) for m in decoded]
        column = reader.column(path)
        if column.dtype == object:
            assert [c.decode() for c in column.tolist()] == expected, path
        else:
            np.testing.assert_array_equal(column, np.array(expected), path)


def test_an_index_past_a_short_sequence_is_an_index_error():
    store = store_for("cdr")
    batch = RawMessages(cdr=True)
    for i, message in enumerate(messages_of(store, "std_msgs/msg/Float64MultiArray",
                                            np.random.default_rng(3))):
        batch.append(i, serialise(store, "cdr", message, "std_msgs/msg/Float64MultiArray"))
    with pytest.raises(IndexError):
        ColumnReader(batch, "std_msgs/msg/Float64MultiArray", store).column("data[3]")


def test_big_endian_cdr_is_left_to_the_per_message_decoder():
    store = store_for("cdr")
    batch = RawMessages(cdr=True)
    for i, message in enumerate(messages_of(store, AWKWARD_TYPE, np.random.default_rng(4))):
        batch.append(i, serialise(store, "cdr", message, AWKWARD_TYPE, little_endian=False))
    with pytest.raises(NotColumnar):
        ColumnReader(batch, AWKWARD_TYPE, store)


def test_a_message_cut_short_is_not_read_past_its_end():
    store = store_for("cdr")
    batch = RawMessages(cdr=True)
    message = messages_of(store, AWKWARD_TYPE, np.random.default_rng(5), 1)[0]
    batch.append(0, serialise(store, "cdr", message, AWKWARD_TYPE)[:-6])
    with pytest.raises(NotColumnar):
        ColumnReader(batch, AWKWARD_TYPE, store).column("big")


@pytest.mark.parametrize("ends", [[9, 104, 304], [9, 106, 301]], ids=["one-size", "sizes"])
def test_messages_gathered_from_a_chunk_read_as_if_appended_one_by_one(ends):
    from adapters.packed import gathered

    data = np.random.default_rng(3).integers(0, 256, 1000, dtype=np.uint8)
    starts = np.array([5, 100, 300])
    one_by_one, at_once = RawMessages(True), RawMessages(True)
    for batch in (one_by_one, at_once):
        batch.append(7, b"earlier")
    for time_ns, (a, b) in enumerate(zip(starts, ends, strict=True)):
        one_by_one.append(time_ns, data[a:b].tobytes())
    at_once.extend(np.arange(3), *gathered(data, starts, np.array(ends)))
    assert at_once.buffer == one_by_one.buffer and at_once.messages() == one_by_one.messages()
    assert list(at_once.times_ns) == list(one_by_one.times_ns) == [7, 0, 1, 2]
