// mc-init: the tetrahedral initialization stage (pipeline/stages/init/init_stage.h).
#include "pipeline/cmd/stage_cli.h"
#include "pipeline/stages/init/init_stage.h"

int main(int argc, char** argv) {
    using namespace mudcrack;
    bool parallel_mesh = false;
    return run_stage(
        "mc-init",
        "Tetrahedral initialization: fills the shot's source (mesh, box or heightfield) with "
        "particles, one per tet vertex",
        argc, argv,
        [&](CLI::App& app) {
            app.add_flag("--parallel-mesh", parallel_mesh,
                         "mesh sources: run CGAL Mesh_3 on all threads (TBB); faster, but the mesh "
                         "then depends on thread timing, so reruns are not bit-identical");
        },
        [&](const StageOptions& options) { return run_init_stage(options, parallel_mesh); });
}
