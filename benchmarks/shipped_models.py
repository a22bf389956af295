"""The shipped models as their model cards describe them: each signal's held-out error, its
skill against the naive predictors and against the least-squares linear model, and the
predictor it is read from, as recorded when the model was scored (`python
scripts/shipped.py score`).

Usage: python benchmarks/shipped_models.py
"""

from datetime import date

# Built-in profiles whose vehicles ship a model.
SHIPPED = ("twin_burger", "three_thruster", "bluerov2")


def _figure(value: float | None, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def main() -> None:
    from auvdiag_cli import api
    from auvdiag_cli.jobs.skill_record import paper_model_error

    lines = [f"Read {date.today()} from the model cards (`api.load_model(profile=…).card`).", "",
             "| model | signal | held-out error (rms) | paper's training error | skill | "
             "vs linear | read from | horizon | scored on |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name in SHIPPED:
        profile = api.load_profile(name)
        model = api.load_model(profile=profile)
        card, paper = model.card, paper_model_error(profile)
        units = {s.name: s.unit for s in profile.sensors}
        for signal in card.sensor_names:
            record = card.skill.get(signal) if card.skill else None
            skill, versus = (None, None) if record is None else (record.skill,
                                                                 record.versus_linear)
            lines.append(
                f"| {name} | {signal} | {_figure(card.heldout_error_rms.get(signal), 4)} "
                f"{units[signal]} | {_figure(paper.get(signal), 4)} | {_figure(skill, 2)} | "
                f"{_figure(versus, 2)} | {card.predictors[signal]} | "
                f"{'free run' if card.horizon_s is None else f'{card.horizon_s:g} s'} | "
                f"{len(card.heldout_logs)} normal dives |")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
