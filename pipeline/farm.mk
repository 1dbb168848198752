# Running shots on a Slurm cluster (scripts in pipeline/farm/). Included by the root
# Makefile; `make shot SHOT=x FARM=slurm` calls farm-submit instead of the local stage rules.
#
#   make shot SHOT=demo FARM=slurm               submit what is not done; returns at once
#   make shot SHOT=demo FARM=slurm FARM_WAIT=1   ... and wait, then report (exit 1 on failure)
#   make farm-status SHOT=demo                   queued, running, done and failed tasks
#   make farm-cluster-start / farm-cluster-stop  a one-node cluster on this machine, in FARM_CLUSTER
#
# Variables: FARM_CHUNK (frames per surfacing and render task, default 4), THREADS (--threads of
# every stage), and from the environment or the command line: FARM_RENDER_CHUNK (frames per
# render task, default FARM_CHUNK), MUDCRACK_PARTITION / SLURM_PARTITION, MUDCRACK_ACCOUNT /
# SLURM_ACCOUNT, FARM_<STAGE>_CPUS|MEM|TIME with STAGE in INIT SIM SURFACE MERGE RENDER ASSEMBLE,
# FARM_SBATCH_ARGS (pipeline/farm/submit.sh documents them).

FARM          ?=
FARM_CHUNK    ?= 4
FARM_WAIT     ?= 0
FARM_SCRIPTS  := pipeline/farm
FARM_CLUSTER  ?= $(OUT)/.slurm

.PHONY: farm-submit farm-status farm-cluster-start farm-cluster-stop

farm-submit:
	@test -n "$(SHOT)" || { echo "usage: make shot SHOT=<name> FARM=slurm"; exit 2; }
	@FARM_CHUNK=$(FARM_CHUNK) $(if $(THREADS),FARM_THREADS=$(THREADS)) \
	  bash $(FARM_SCRIPTS)/submit.sh --shot shots/$(SHOT).json --out $(OUT)/$(SHOT) --bin $(BUILD)/bin \
	  $(if $(filter 1 yes,$(FARM_WAIT)),--wait && $(BUILD)/bin/mc-shot summary $(OUT)/$(SHOT))

farm-status:
	@test -n "$(SHOT)" || { echo "usage: make farm-status SHOT=<name>"; exit 2; }
	@bash $(FARM_SCRIPTS)/status.sh --out $(OUT)/$(SHOT)

farm-cluster-start:
	@bash $(FARM_SCRIPTS)/slurm_local_cluster.sh start $(FARM_CLUSTER)
	@echo "mudcrack: now run: export SLURM_CONF=$(abspath $(FARM_CLUSTER))/slurm.conf"

farm-cluster-stop:
	@bash $(FARM_SCRIPTS)/slurm_local_cluster.sh stop $(FARM_CLUSTER)
