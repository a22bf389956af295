"""Byte-level damage of the kinds field logs show, applied to a valid log: flipped bits,
overwritten runs, length and count fields set to absurd values, truncation, duplicated,
deleted and swapped blocks. Every mutation is a pure function of the bytes and a seeded
random generator, so a case is reproduced from its seed alone."""

import random
from collections.abc import Callable
from typing import Literal

Mutation = Callable[[bytearray, random.Random], str]

# Values a damaged 2/4/8-byte length or count field takes: zero, all ones (huge unsigned,
# -1 signed), the sign bit (most negative), the largest positive, a merely large value.
_FIELD_VALUES = ("zero", "all-ones", "sign-bit", "max-positive", "large")


def _offset(data: bytearray, rng: random.Random, room: int = 1) -> int:
    return rng.randrange(max(1, len(data) - room + 1))


def flip_bits(data: bytearray, rng: random.Random) -> str:
    flips = rng.randint(1, 8)
    for _ in range(flips):
        data[_offset(data, rng)] ^= 1 << rng.randrange(8)
    return f"flip {flips} bit(s)"


def random_run(data: bytearray, rng: random.Random) -> str:
    size = min(len(data), rng.choice((1, 2, 4, 8, 16, 64, 256)))
    at = _offset(data, rng, size)
    data[at:at + size] = rng.randbytes(size)
    return f"{size} random bytes at {at}"


def length_field(data: bytearray, rng: random.Random) -> str:
    width = rng.choice((2, 4, 8))
    if len(data) < width:
        return "no room for a field"
    at = _offset(data, rng, width)
    kind = rng.choice(_FIELD_VALUES)
    bits = 8 * width
    value = {"zero": 0, "all-ones": (1 << bits) - 1, "sign-bit": 1 << (bits - 1),
             "max-positive": (1 << (bits - 1)) - 1,
             "large": rng.randrange(1 << (bits - 4), 1 << (bits - 1))}[kind]
    order: Literal["little", "big"] = "little" if rng.random() < 0.5 else "big"
    data[at:at + width] = value.to_bytes(width, order)
    return f"{width}-byte field at {at} set to {kind} ({order}-endian)"


def truncate(data: bytearray, rng: random.Random) -> str:
    keep = rng.randrange(len(data)) if data else 0
    del data[keep:]
    return f"truncated to {keep} bytes"


def _block(data: bytearray, rng: random.Random) -> tuple[int, int]:
    size = min(len(data), rng.choice((8, 64, 512, 4096)))
    start = _offset(data, rng, size)
    return start, start + size


def duplicate_block(data: bytearray, rng: random.Random) -> str:
    start, end = _block(data, rng)
    at = _offset(data, rng)
    data[at:at] = data[start:end]
    return f"bytes {start}-{end} repeated at {at}"


def delete_block(data: bytearray, rng: random.Random) -> str:
    start, end = _block(data, rng)
    del data[start:end]
    return f"bytes {start}-{end} deleted"


def swap_blocks(data: bytearray, rng: random.Random) -> str:
    first, second = sorted((_block(data, rng), _block(data, rng)))
    if first[1] > second[0]:
        return "no two separate blocks"
    a, b = bytes(data[first[0]:first[1]]), bytes(data[second[0]:second[1]])
    data[second[0]:second[1]] = a
    data[first[0]:first[1]] = b
    return f"bytes {first[0]}-{first[1]} swapped with {second[0]}-{second[1]}"


MUTATIONS: tuple[Mutation, ...] = (flip_bits, random_run, length_field, truncate,
                                   duplicate_block, delete_block, swap_blocks)


def mutate(data: bytes, seed: int) -> tuple[bytes, list[str]]:
    """One to three mutations of ``data``, chosen and placed by ``seed``."""
    rng = random.Random(seed)
    damaged = bytearray(data)
    done = []
    for _ in range(rng.choice((1, 1, 2, 3))):
        if not damaged:          # truncated to nothing: no more to damage
            break
        done.append(rng.choice(MUTATIONS)(damaged, rng))
    return bytes(damaged), done
