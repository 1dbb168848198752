# Per-shot stage rules (included by the root Makefile). Each stage's target is its manifest; its
# prerequisites are the previous stage's manifest, the stage binary, and the stage's slice of the
# shot (OUT/<shot>/<stage>.params.json), which `mc-shot slice` rewrites only when its content
# changes. So editing only a render key re-runs only the render, and a second run does nothing.
#
#   make shot SHOT=demo          all stages the shot enables, in order
#   make clean-shot SHOT=demo

SHOT_FILE  = shots/$(SHOT).json
SHOT_OUT   = $(OUT)/$(SHOT)
BIN        = $(BUILD)/bin
# the stages this shot enables (init sim [surface] [render]), as mc-shot reads them
SHOT_STAGES = $(shell $(BIN)/mc-shot stages $(SHOT_FILE) 2>/dev/null)
STAGE_FLAGS = --shot $(SHOT_FILE) --out $(SHOT_OUT) $(if $(THREADS),--threads $(THREADS))

# slices: always re-derived, rewritten only on change (mtime moves only then)
$(SHOT_OUT)/%.params.json: FORCE
	@mkdir -p $(SHOT_OUT)
	@$(BIN)/mc-shot slice $(SHOT_FILE) $* --out $@

$(SHOT_OUT)/init/manifest.json: $(SHOT_OUT)/init.params.json $(BIN)/mc-init
	$(BIN)/mc-init $(STAGE_FLAGS)

$(SHOT_OUT)/sim/manifest.json: $(SHOT_OUT)/init/manifest.json $(SHOT_OUT)/sim.params.json $(BIN)/mc-sim
	$(BIN)/mc-sim $(STAGE_FLAGS) $(if $(wildcard $(SHOT_OUT)/sim/checkpoint.*.bin),--resume)

$(SHOT_OUT)/surface/manifest.json: $(SHOT_OUT)/sim/manifest.json $(SHOT_OUT)/surface.params.json $(BIN)/mc-surface
	$(BIN)/mc-surface $(STAGE_FLAGS)

$(SHOT_OUT)/render/manifest.json: $(SHOT_OUT)/$(if $(filter surface,$(SHOT_STAGES)),surface,sim)/manifest.json \
                                  $(SHOT_OUT)/render.params.json $(BIN)/mc-render
	$(BIN)/mc-render $(STAGE_FLAGS)

.PHONY: FORCE shot-run shot-summary
FORCE:

shot-run: $(foreach s,$(SHOT_STAGES),$(SHOT_OUT)/$(s)/manifest.json)

shot-summary:
	@$(BIN)/mc-shot summary $(SHOT_OUT)
