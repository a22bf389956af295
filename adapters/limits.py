"""Sizes the readers accept from a file before trusting them. Decoders read untrusted bytes:
a length or count field is checked against these (and against the bytes that remain) before
anything is allocated from it."""

# Writers compress in chunks of about 1-4 MiB (the mcap library 1 MiB, rosbag2 768 KiB,
# rosbag 768 KiB); a chunk declaring more than this uncompressed is taken to be damaged.
MAX_CHUNK_BYTES = 256 << 20
