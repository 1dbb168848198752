# Per-shot stage rules (included by the root Makefile). Each stage's target is its manifest; its
# prerequisites are the previous stage's manifest, the stage binary, and the stage's slice of the
# shot (OUT/<shot>/<stage>.params.json), which `mc-shot slice` rewrites only when its content
# changes. So editing only a render key re-runs only the render, and a second run does nothing.
#
#   make shot SHOT=demo                 all stages the shot enables, in order
#   make -j2 shot SHOT=demo             surfacing and rendering in frame chunks, 2 at a time
#   make shot SHOT=demo SHOT_CHUNK=8    chunks of 8 frames (with or without -j)
#   make clean-shot SHOT=demo
#
# Surfacing and rendering run in a sub-make of this file (the shot-stage-surface and
# shot-stage-render goals). Serial and without SHOT_CHUNK it runs mc-surface / mc-render over all
# frames; under -jN (or with SHOT_CHUNK) it runs the farm's chunk tasks (pipeline/farm/task.sh, as
# Slurm does): a first surfacing chunk that also computes the edge-break history, the other
# chunks in private work folders, a merge of their manifests, render chunks (mc-render --frames)
# and the assembly (mc-render --assemble). The files are byte-identical to the serial run's.
# Chunk tasks log to OUT/<shot>/logs/<task>.log; a failed one prints its log's last lines.
# Variables: THREADS (--threads of every stage; by default a chunk gets its share of the cores),
# SHOT_CHUNK (frames per chunk; by default one render chunk per make job, and one surfacing chunk
# per job after the first).
#
# A shot with /reuse (e.g. fig9: "reuse": "fig8_c") shares the outputs of another shot of the
# same folder: every stage whose slice file is byte-identical to that shot's (so are the stages
# before it, whose keys each slice holds) is brought up to date by a make of the other shot
# limited to those stages, then OUT/<shot>/<stage> is a relative symlink to ../<other>/<stage>
# (the stages read DIR/<stage>/ and check its manifest's slice hash, which matches). Only the
# stages that differ run in OUT/<shot>/. A link whose stage no longer matches is removed when the
# makefile is read, so a stage never writes into the other shot's folder. `make clean-shot`
# removes the links, never the files they point at. FARM=slurm refuses such a shot.

SHOT_MK     := $(lastword $(MAKEFILE_LIST))
SHELL       := /bin/bash
FARM_SCRIPTS ?= pipeline/farm
SHOT_FILE  = shots/$(SHOT).json
SHOT_OUT   = $(OUT)/$(SHOT)
BIN        = $(BUILD)/bin
# the stages this shot enables (init sim [surface] [render]), as mc-shot reads them
SHOT_STAGES = $(shell $(BIN)/mc-shot stages $(SHOT_FILE) 2>/dev/null)
STAGE_FLAGS = --shot $(SHOT_FILE) --out $(SHOT_OUT) $(if $(THREADS),--threads $(THREADS))
# the sub-make that runs a per-frame stage (OUT and BUILD are the root Makefile's, not command-line
# variables, so they are passed on); its recipe lines start with + so it shares the jobserver
STAGE_MAKE = $(MAKE) --no-print-directory -f $(SHOT_MK) SHOT=$(SHOT) OUT=$(OUT) BUILD=$(BUILD) \
             FARM_SCRIPTS=$(FARM_SCRIPTS) $(if $(THREADS),THREADS=$(THREADS)) $(if $(SHOT_CHUNK),SHOT_CHUNK=$(SHOT_CHUNK))
RENDER_SOURCE = $(if $(filter surface,$(SHOT_STAGES)),surface,sim)

# ---- /reuse: the stages shared with another shot ----------------------------------------------
# /reuse, as the shot loader reads (and checks) it; empty when unset or when the shot is invalid
# (the stage rules then report the shot's errors)
SHOT_REUSE := $(shell $(BIN)/mc-shot reuse $(SHOT_FILE) 2>/dev/null)
SHOT_SHARED :=
# the chunk sub-makes (shot-stage-*) and the farm do not link: only the make that runs the stages
ifeq ($(filter shot-stage-% farm-%,$(MAKECMDGOALS)),)
ifneq ($(SHOT_REUSE),)
REUSE_FILE   := $(dir $(SHOT_FILE))$(SHOT_REUSE).json
REUSE_OUT    := $(OUT)/$(SHOT_REUSE)
REUSE_STAGES := $(shell $(BIN)/mc-shot stages $(REUSE_FILE))
$(if $(REUSE_STAGES),,$(error $(SHOT_FILE): /reuse = "$(SHOT_REUSE)": $(REUSE_FILE) is not a valid shot (see above)))
# shared: the leading stages both shots run whose slice files (written here, as the slice rule
# below writes them: only on change) are byte-identical; each slice holds the earlier stages'
# keys, so the first stage that differs ends the sharing
SHOT_SHARED := $(shell for s in $(SHOT_STAGES); do \
    [[ " $(REUSE_STAGES) " == *" $$s "* ]] || break; \
    $(BIN)/mc-shot slice $(SHOT_FILE) $$s --out $(SHOT_OUT)/$$s.params.json 2>/dev/null && \
    $(BIN)/mc-shot slice $(REUSE_FILE) $$s --out $(REUSE_OUT)/$$s.params.json 2>/dev/null && \
    cmp -s $(SHOT_OUT)/$$s.params.json $(REUSE_OUT)/$$s.params.json || break; \
    echo $$s; done)
$(if $(SHOT_SHARED),,$(info mudcrack: $(SHOT): /reuse = "$(SHOT_REUSE)", but their init slices differ: nothing is shared))
endif
# a link left from an earlier run whose stage is not shared now: removed before anything can write
# through it into the other shot's folder (rm of a link never touches its target)
$(shell for s in $(filter-out $(SHOT_SHARED),init sim surface render); do \
    if [ -L $(SHOT_OUT)/$$s ]; then echo "mudcrack: $(SHOT)/$$s: removed the link to $$(readlink $(SHOT_OUT)/$$s)" \
    "(the stage is not shared now)" >&2; rm -f $(SHOT_OUT)/$$s; fi; done)
endif

# brings the other shot's shared stages up to date: this makefile for that shot, asked only for
# them (shot-stages); it shares the jobserver
.PHONY: shot-reuse-upstream shot-stages
shot-reuse-upstream:
	@+$(MAKE) --no-print-directory -f $(SHOT_MK) shot-stages SHOT=$(SHOT_REUSE) SHOT_FILE=$(REUSE_FILE) \
	    SHOT_STAGES_WANTED="$(SHOT_SHARED)" OUT=$(OUT) BUILD=$(BUILD) BIN=$(BIN) FARM_SCRIPTS=$(FARM_SCRIPTS) \
	    $(if $(THREADS),THREADS=$(THREADS)) $(if $(SHOT_CHUNK),SHOT_CHUNK=$(SHOT_CHUNK))

# the stages SHOT_STAGES_WANTED of this shot, and nothing after them
shot-stages: $(foreach s,$(SHOT_STAGES_WANTED),$(SHOT_OUT)/$(s)/manifest.json)
	@:

# a shared stage: OUT/<shot>/<stage> -> ../<other>/<stage>, (re)made when it is not that link yet
# (a folder of this shot's own earlier run is removed: it is this shot's, and stale now)
define shared_stage_rule
$(SHOT_OUT)/$(1)/manifest.json: shot-reuse-upstream
	@if [ "$$$$(readlink $(SHOT_OUT)/$(1))" != ../$(SHOT_REUSE)/$(1) ]; then \
	    rm -rf $(SHOT_OUT)/$(1) && ln -s ../$(SHOT_REUSE)/$(1) $(SHOT_OUT)/$(1) && \
	    echo "mudcrack: $(SHOT)/$(1) -> ../$(SHOT_REUSE)/$(1) (same slice as $(SHOT_REUSE)'s $(1): shared, not run)"; fi
endef
$(foreach s,$(SHOT_SHARED),$(eval $(call shared_stage_rule,$(s))))

# slices: always re-derived, rewritten only on change (mtime moves only then)
$(SHOT_OUT)/%.params.json: FORCE
	@mkdir -p $(SHOT_OUT)
	@$(BIN)/mc-shot slice $(SHOT_FILE) $* --out $@

# the shot's own stages (those not shared)
ifeq ($(filter init,$(SHOT_SHARED)),)
$(SHOT_OUT)/init/manifest.json: $(SHOT_OUT)/init.params.json $(BIN)/mc-init
	$(BIN)/mc-init $(STAGE_FLAGS)
endif

ifeq ($(filter sim,$(SHOT_SHARED)),)
$(SHOT_OUT)/sim/manifest.json: $(SHOT_OUT)/init/manifest.json $(SHOT_OUT)/sim.params.json $(BIN)/mc-sim
	$(BIN)/mc-sim $(STAGE_FLAGS) $(if $(wildcard $(SHOT_OUT)/sim/checkpoint.*.bin),--resume)
endif

ifeq ($(filter surface,$(SHOT_SHARED)),)
$(SHOT_OUT)/surface/manifest.json: $(SHOT_OUT)/sim/manifest.json $(SHOT_OUT)/surface.params.json $(BIN)/mc-surface
	@+$(STAGE_MAKE) shot-stage-surface
endif

ifeq ($(filter render,$(SHOT_SHARED)),)
$(SHOT_OUT)/render/manifest.json: $(SHOT_OUT)/$(RENDER_SOURCE)/manifest.json \
                                  $(SHOT_OUT)/render.params.json $(BIN)/mc-render
	@+$(STAGE_MAKE) shot-stage-render
endif

# the farm path does not link stages: a reuse shot is refused before submit.sh runs
farm-submit: shot-farm-no-reuse
.PHONY: shot-farm-no-reuse
shot-farm-no-reuse:
	@if [ -n "$(SHOT_REUSE)" ]; then \
	    echo "mudcrack: $(SHOT): FARM=slurm does not support /reuse = \"$(SHOT_REUSE)\" (the farm does not link" \
	         "shared stages): run it without FARM=slurm, or drop /reuse from $(SHOT_FILE)" >&2; exit 1; fi

.PHONY: FORCE shot-run shot-summary
FORCE:

shot-run: $(foreach s,$(SHOT_STAGES),$(SHOT_OUT)/$(s)/manifest.json)

# after the stages, also under -jN (the root Makefile asks for shot-run shot-summary)
shot-summary: shot-run
	@$(BIN)/mc-shot summary $(SHOT_OUT)

# ---- the sub-make of one per-frame stage: shot-stage-surface, shot-stage-render ------------------
ifneq ($(filter shot-stage-%,$(MAKECMDGOALS)),)
# GNU make 4.3 gives a sub-make its parent's -jN in the environment's MAKEFLAGS only (the makefile
# variable lacks it while parsing); "-j" alone means no limit: one job per core then.
SHOT_NPROC := $(shell nproc)
SHOT_JFLAG := $(filter -j%,$(shell echo "$$MAKEFLAGS"))
SHOT_JOBS  := $(if $(SHOT_JFLAG),$(or $(patsubst -j%,%,$(SHOT_JFLAG)),$(SHOT_NPROC)),1)
$(if $(SHOT_CHUNK),$(if $(shell [[ "$(SHOT_CHUNK)" =~ ^[1-9][0-9]*$$ ]] && echo ok),,\
    $(error SHOT_CHUNK=$(SHOT_CHUNK): expected a whole number of frames >= 1)))
# chunks only under -jN or with SHOT_CHUNK: a serial run is one stage binary over every frame
ifeq ($(or $(SHOT_CHUNK),$(filter-out 1,$(SHOT_JOBS))),)
SURFACE_CHUNKS := all
RENDER_CHUNKS  := all
else
# the frame range, from the sim slice the parent make has just brought up to date
SHOT_FRAMES := $(shell jq -r '"\(.frames.start) \(.frames.end)"' $(SHOT_OUT)/sim.params.json)
$(if $(word 2,$(SHOT_FRAMES)),,$(error $(SHOT_OUT)/sim.params.json: no frame range (is jq installed?)))
shot_first := $(word 1,$(SHOT_FRAMES))
shot_count := $(shell echo $$(( $(word 2,$(SHOT_FRAMES)) - $(shot_first) + 1 )))
ceil_div = $(shell echo $$(( ($(1) + ($(2)) - 1) / ($(2)) )))
# frames per chunk: the first surfacing chunk runs alone (it computes the break history), so the
# surfacing is split one chunk more than the jobs
SURFACE_CHUNK := $(or $(SHOT_CHUNK),$(call ceil_div,$(shot_count),$(SHOT_JOBS) + 1))
RENDER_CHUNK  := $(or $(SHOT_CHUNK),$(call ceil_div,$(shot_count),$(SHOT_JOBS)))
# the chunks, "A-B" each, split exactly as pipeline/farm/submit.sh splits them
frame_chunks = $(shell source $(FARM_SCRIPTS)/farm_lib.sh && seq $(shot_first) $(word 2,$(SHOT_FRAMES)) | \
                 farm_chunk_frames $(1) | tr ' ' -)
SURFACE_CHUNKS := $(call frame_chunks,$(SURFACE_CHUNK))
RENDER_CHUNKS  := $(call frame_chunks,$(RENDER_CHUNK))
endif
# threads: a task that runs alone gets every core, concurrent chunks share them
ALONE_THREADS := $(or $(THREADS),$(SHOT_NPROC))
CHUNK_THREADS := $(or $(THREADS),$(shell echo $$(( $(SHOT_NPROC) / $(SHOT_JOBS) > 0 ? $(SHOT_NPROC) / $(SHOT_JOBS) : 1 ))))

# stage_task KIND FRAMES THREADS: one chunk task (pipeline/farm/task.sh) on this machine
stage_task = echo "mudcrack: $(SHOT): $(1)$(if $(2), frames $(2)) ($(3) threads; log $(SHOT_OUT)/logs/)"; \
    FARM_THREADS=$(3) bash $(FARM_SCRIPTS)/task.sh $(1) $(SHOT_FILE) $(SHOT_OUT) $(BIN) $(subst -, ,$(2))

.PHONY: shot-stage-surface shot-stage-render $(addprefix surface-chunk-,$(SURFACE_CHUNKS)) \
        $(addprefix render-chunk-,$(RENDER_CHUNKS))
ifeq ($(words $(SURFACE_CHUNKS)),1)
shot-stage-surface:
	$(BIN)/mc-surface $(STAGE_FLAGS)
else
surface-chunk-$(firstword $(SURFACE_CHUNKS)):
	@$(call stage_task,surface-prep,$(firstword $(SURFACE_CHUNKS)),$(ALONE_THREADS))
$(addprefix surface-chunk-,$(wordlist 2,$(words $(SURFACE_CHUNKS)),$(SURFACE_CHUNKS))): \
        surface-chunk-%: surface-chunk-$(firstword $(SURFACE_CHUNKS))
	@$(call stage_task,surface-chunk,$*,$(CHUNK_THREADS))
shot-stage-surface: $(addprefix surface-chunk-,$(SURFACE_CHUNKS))
	@$(call stage_task,surface-merge,,1)
endif

ifeq ($(words $(RENDER_CHUNKS)),1)
shot-stage-render:
	$(BIN)/mc-render $(STAGE_FLAGS)
else
$(addprefix render-chunk-,$(RENDER_CHUNKS)): render-chunk-%:
	@$(call stage_task,render-chunk,$*,$(CHUNK_THREADS))
shot-stage-render: $(addprefix render-chunk-,$(RENDER_CHUNKS))
	@$(call stage_task,render-assemble,,$(ALONE_THREADS))
endif
endif
