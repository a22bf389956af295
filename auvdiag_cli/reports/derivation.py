"""What `auvdiag derive-table` prints: each single fault's b on every DMS and the mission,
the pattern table those imply, and whether it matches the profile's."""

from collections.abc import Sequence

from auvdiag_cli.engine.signatures import DerivedTable


def derivation_lines(result: DerivedTable, sensor_names: Sequence[str]) -> list[str]:
    modes = list(result.signatures[0].b)
    lines = ["b signatures (" + ", ".join(sensor_names) + ") of each single fault:",
             f"  {'component':<18}" + "".join(f"{mode:>10}" for mode in modes)]
    for signature in result.signatures:
        cells = ["".join(str(signature.b[mode][n]) for n in sensor_names) for mode in modes]
        lines.append(f"  {signature.component:<18}" + "".join(f"{c:>10}" for c in cells))
    lines.append("pattern table derived from the mission signatures:")
    for row in result.rows:
        bits = ", ".join(f"{n}={row.b[n]}" for n in sensor_names)
        lines.append(f"  case {row.case}: {bits}  ->  "
                     + (" or ".join(row.components) or "nothing"))
    if result.unseen_on_mission:
        lines.append("  not seen on the mission (only on the DMSs above): "
                     + ", ".join(result.unseen_on_mission))
    lines.append("matches the profile's table" if result.matches_profile
                 else "DIFFERS from the profile's table")
    return lines
