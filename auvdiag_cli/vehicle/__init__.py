"""The vehicle described: its profile (signals, sources, thresholds, pattern table, DMSs),
the TOML it is read from, its controller and the physics the simulator flies it with."""
