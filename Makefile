# EHC-MM entry points. Every target installs its Debian packages first (idempotent).
#   make demo   - the main job: headless simulated run (see README)
#   make test   - every gtest + rostest, closing line "N passed, N failed"
#   make bench  - benchmarks, one JSON object per line
#   make experiments - paper Exp-1..3 in-process -> results/experiments/REPORT.md
#   make validate - Exp-1 reaching on a fresh random seed, every robot x generator x method -> results/validate
#   make results - docs/RESULTS.md from the result folders under results/ (missing ones: "not run")
#   make sweep - Exp-1 (both protocols), Exp-2, Exp-3 x method x imprecision level x seeds, 95 % CIs -> results/sweep
SHELL := /bin/bash
.SHELLFLAGS := -eo pipefail -c
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)

JOBS ?= 2
CATKIN := catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release -j$(JOBS)

.PHONY: all deps build demo test bench experiments clean
.PHONY: results validate sweep everyday

all: build

deps:
	@src/ehc_bringup/scripts/install_deps.sh

build: deps
	$(CATKIN)

# make demo ROBOT=kuka_iiwa14_kmr: another robot (config/robots/<name>/ or a robot.yaml path)
demo: build
	ROBOT="$(ROBOT)" src/ehc_bringup/scripts/demo.sh

test: deps
	JOBS=$(JOBS) test/run_tests.sh

bench: build
	src/ehc_bringup/scripts/bench.sh

experiments: build
	ROBOT="$(ROBOT)" src/ehc_bringup/scripts/experiments.sh

# Exp-2 on the object library, both halves (TUNING_SEEDS=a VALIDATION_SEEDS=b,c,d: rerun; default fresh, printed).
everyday: build
	JOBS=$(JOBS) ROBOT="$(ROBOT)" src/ehc_bringup/scripts/everyday.sh

# SEED=123: rerun a validation; default a fresh random seed (printed first).
validate: build
	/usr/bin/python3 src/ehc_bringup/scripts/validate.py --out "$(or $(OUT),results/validate)" --jobs $(JOBS) \
	  --sets $(or $(VALIDATE_SETS),4) --points $(or $(VALIDATE_POINTS),50) $(if $(SEED),--seed $(SEED))

# SEEDS=a,b,...: rerun a sweep (default SWEEP_SEEDS [10] fresh reporting seeds, printed first);
# LEVELS [0,1,2,4]; SHARD=K/N runs one part (needs SEEDS), then sweep.py merge (README).
sweep: build
	/usr/bin/python3 src/ehc_bringup/scripts/sweep.py run --out "$(or $(OUT),results/sweep)" --jobs $(JOBS) \
	  --seed-count $(or $(SWEEP_SEEDS),10) $(if $(SEEDS),--seeds $(SEEDS)) $(if $(LEVELS),--levels $(LEVELS)) \
	  $(if $(SHARD),--shard $(SHARD))

clean:
	rm -rf build devel install

# No build needed: reads results/experiments, results/bench, results/demo (whatever exists).
results: deps
	/usr/bin/python3 src/ehc_bringup/scripts/make_results.py
