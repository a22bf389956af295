"""What every ROS 2 bag's adapter shares: a bag whose messages rosbag2 compressed itself is
read through rosbags (`adapters.rosbag2_compressed`); any other from its storage files, by
the storage's own reader (db3: `adapters.rosbag2_sqlite`, MCAP: `adapters.mcap`)."""

from abc import ABC, abstractmethod
from pathlib import Path

from adapters.collect import SignalCollector
from adapters.inventory import LogInventory
from adapters.recognise import bag_metadata, bag_storages
from adapters.rosbag2_compressed import (
    compressed_by_rosbag2,
    compressed_inventory,
    read_compressed,
)
from adapters.signals import LogSources, Signals


class Rosbag2Adapter(ABC):
    """A ROS 2 bag: its folder, or one of its storage files."""

    family = "ros"

    def read(self, path: Path, sources: LogSources, fmt: str) -> Signals:
        if compressed_by_rosbag2(bag_metadata(path)):
            return read_compressed(path, SignalCollector(path, sources), fmt)
        return self.read_storages(bag_storages(path), path, sources, fmt)

    def inventory(self, path: Path, fmt: str) -> LogInventory:
        if compressed_by_rosbag2(bag_metadata(path)):
            return compressed_inventory(path, fmt)
        return self.storages_inventory(bag_storages(path), path, fmt)

    @abstractmethod
    def read_storages(self, storages: list[Path], path: Path, sources: LogSources, fmt: str
                      ) -> Signals: ...

    @abstractmethod
    def storages_inventory(self, storages: list[Path], path: Path, fmt: str
                           ) -> LogInventory: ...
