# `make bench` reruns every benchmark and rewrites its figures in the docs pages (with the
# machine and the date). About two hours on 2 cores: the 200-log audit and the fuzzing
# campaign (86 000 damaged logs, about 35 min) take most of it.
PYTHON ?= .venv/bin/python
OUT := .bench

.PHONY: bench bench-reference bench-detection bench-ingest bench-speed bench-audit bench-fuzz \
	bench-train bench-train-busy bench-real bench-alfa bench-hidden bench-effort bench-effort-band bench-few bench-whole bench-shipped bench-samples bench-silence test model \
	samples

bench: bench-reference bench-detection bench-ingest bench-speed bench-audit bench-silence bench-fuzz \
	bench-train bench-train-busy bench-real bench-alfa bench-hidden bench-effort bench-effort-band bench-few bench-whole bench-shipped bench-samples

bench-reference:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/reference_experiment.py --seeds 20 > $(OUT)/reference.md
	$(PYTHON) benchmarks/readme.py reference $(OUT)/reference.md

bench-detection:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/detection.py --seeds 2 --normal-seeds 12 > $(OUT)/detection.md
	$(PYTHON) benchmarks/readme.py detection $(OUT)/detection.md

bench-ingest:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/ingest.py > $(OUT)/ingest.md
	$(PYTHON) benchmarks/readme.py ingest $(OUT)/ingest.md

bench-speed:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/speed.py > $(OUT)/speed.md
	$(PYTHON) benchmarks/readme.py speed $(OUT)/speed.md

bench-audit:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/audit.py --logs 200 --jobs 2 > $(OUT)/audit.md
	$(PYTHON) benchmarks/readme.py audit $(OUT)/audit.md

bench-silence:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/silence.py > $(OUT)/silence.md
	$(PYTHON) benchmarks/readme.py silence $(OUT)/silence.md

bench-fuzz:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/fuzz.py --cases 10000 --real-cases 2000 --json $(OUT)/fuzz.json > $(OUT)/fuzz.md
	$(PYTHON) benchmarks/readme.py fuzz $(OUT)/fuzz.md

bench-train:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/train.py > $(OUT)/train.md
	$(PYTHON) benchmarks/readme.py train $(OUT)/train.md

bench-train-busy:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/train.py --busy --iterations-scale 0.1 > $(OUT)/train_busy.md
	$(PYTHON) benchmarks/readme.py train_busy $(OUT)/train_busy.md

bench-shipped:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/shipped_models.py > $(OUT)/shipped_models.md
	$(PYTHON) benchmarks/readme.py shipped_models $(OUT)/shipped_models.md

bench-samples:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/sample_facts.py > $(OUT)/sample_facts.md
	$(PYTHON) benchmarks/readme.py sample_facts $(OUT)/sample_facts.md
	$(PYTHON) benchmarks/sample_facts.py --catalogue > $(OUT)/sample_logs.md
	$(PYTHON) benchmarks/readme.py sample_logs $(OUT)/sample_logs.md

bench-alfa:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/alfa.py > $(OUT)/alfa.md
	$(PYTHON) benchmarks/readme.py alfa $(OUT)/alfa.md

bench-real:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/real_data.py > $(OUT)/real_data.md
	$(PYTHON) benchmarks/readme.py real_data $(OUT)/real_data.md

test:
	$(PYTHON) -m ruff check . && $(PYTHON) -m mypy && $(PYTHON) -m pytest -q

bench-hidden:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/hidden_faults.py --seeds 3 --jobs 2 > $(OUT)/hidden_faults.md
	$(PYTHON) benchmarks/readme.py hidden_faults $(OUT)/hidden_faults.md

bench-effort:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/effort.py > $(OUT)/effort.md
	$(PYTHON) benchmarks/readme.py effort $(OUT)/effort.md

bench-effort-band:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/effort_band.py > $(OUT)/effort_band.md
	$(PYTHON) benchmarks/readme.py effort_band $(OUT)/effort_band.md

bench-few:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/few_logs.py > $(OUT)/few_logs.md
	$(PYTHON) benchmarks/readme.py few_logs $(OUT)/few_logs.md

bench-whole:
	@mkdir -p $(OUT)
	$(PYTHON) benchmarks/whole_tool_crazypad.py > $(OUT)/whole_tool_crazypad.md
	$(PYTHON) benchmarks/readme.py whole_tool_crazypad $(OUT)/whole_tool_crazypad.md

# What the project ships, rebuilt from simulated dives (scripts/shipped.py):
# `make model PROFILE=three_thruster` (twin_burger by default), `make samples`.
PROFILE ?= twin_burger

model:
	$(PYTHON) scripts/shipped.py model $(PROFILE)

samples:
	$(PYTHON) scripts/shipped.py samples
	$(MAKE) bench-samples
