// mc-report: `make report`. Accuracy sweeps against analytic solutions with their
// Pareto plots, and the stability matrix, written to <out>/report.md.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "sim/core/error.h"
#include "sim/core/log.h"
#include "sim/core/parallel.h"
#include "tools/report/accuracy.h"
#include "tools/report/format.h"
#include "tools/report/machine_info.h"
#include "tools/report/report_writer.h"
#include "tools/report/scenes.h"
#include "tools/report/stability.h"

namespace fs = std::filesystem;
using namespace mudcrack;
using namespace mudcrack::report;

namespace {

std::string joined_command(int argc, char** argv) {
    std::string s = "mc-report";
    for (int i = 1; i < argc; ++i) s += std::string(" ") + argv[i];
    return s;
}

int run(int argc, char** argv) {
    CLI::App app{
        "mc-report: error against run time and the stability matrix (writes <out>/report.md)"};
    std::string out = "out/report", only_case;
    bool is_quick = false, is_listing = false, skip_accuracy = false, skip_stability = false;
    int threads = 0;
    app.add_option("--out", out, "report folder")->capture_default_str();
    app.add_flag("--quick", is_quick,
                 "reduced scale: small grids, few steps (what make test runs)");
    app.add_option("--threads", threads, "worker threads (0: all cores)")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--case", only_case,
                   "run one stability case in this process and print its result line");
    app.add_flag("--list-cases", is_listing, "list the stability cases");
    app.add_flag("--skip-accuracy", skip_accuracy, "leave out the accuracy sweeps");
    app.add_flag("--skip-stability", skip_stability, "leave out the stability matrix");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    log::set_program("mc-report");
    set_thread_count(threads);
    const Scale scale = is_quick ? Scale::Reduced : Scale::Full;

    if (is_listing) {
        for (const StabilityCase& c : stability_cases())
            std::printf("%-30s %-18s %s\n", c.name.c_str(), c.group.c_str(), c.description.c_str());
        return 0;
    }
    if (!only_case.empty()) {
        const StabilityResult r = run_stability_case(only_case, scale, stability_limits(scale));
        std::printf("%s\n", serialize_result(r).c_str());
        return 0;
    }

    const WallClock total;
    ReportContent content;
    content.machine = machine_info(MUDCRACK_SOURCE_DIR);
    content.command = joined_command(argc, argv);
    content.threads = thread_count();
    content.scale = scale;

    if (!skip_accuracy) {
        const WallClock clock;
        std::fprintf(stderr, "mc-report: accuracy sweeps...\n");
        content.sweeps = all_sweeps(scale, [&](const Sweep& s) {
            double wall = 0;
            for (const SweepPoint& p : s.points) wall += p.wall_s;
            std::fprintf(stderr, "mc-report:   %-22s order %6.2f  (%.1f s, at %.0f s)\n",
                         s.id.c_str(), s.order, wall, total.seconds());
        });
        content.accuracy_wall_s = clock.seconds();
    }
    if (!skip_stability) {
        const WallClock clock;
        const std::string exe = fs::read_symlink("/proc/self/exe").string();
        content.cases = stability_cases();
        for (const StabilityCase& c : content.cases) {
            StabilityResult r =
                run_stability_case_isolated(exe, c.name, scale, stability_limits(scale), 1);
            std::fprintf(stderr, "mc-report:   %-30s %s (%lld steps, %.1f s)\n", c.name.c_str(),
                         outcome_name(r.outcome), static_cast<long long>(r.steps), r.wall_s);
            content.stability.push_back(std::move(r));
        }
        content.stability_wall_s = clock.seconds();
    }

    const fs::path dir(out);
    fs::create_directories(dir);
    const std::vector<Figure> figures = write_figures(dir, content.sweeps);
    content.total_wall_s = total.seconds();
    write_text_file(dir / "report.md", report_markdown(content, figures));
    std::printf("mc-report: wrote %s (%.1f s)\n", (dir / "report.md").string().c_str(),
                content.total_wall_s);

    int failures = 0;
    for (const StabilityResult& r : content.stability) failures += is_product_failure(r.outcome);
    if (failures > 0) {
        std::fprintf(
            stderr,
            "mc-report: error: %d stability case(s) failed (silent NaN, hang or crash); see %s\n",
            failures, (dir / "report.md").string().c_str());
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "mc-report: error: %s\n", e.what());
        return 1;
    }
}
