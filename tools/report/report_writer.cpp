#include "tools/report/report_writer.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "sim/core/error.h"
#include "sim/mpm/step_retry.h"
#include "tools/report/format.h"

namespace mudcrack::report {

namespace fs = std::filesystem;

namespace {

// a gnuplot single-quoted string (a quote is doubled)
std::string gp_quote(const std::string& s) {
    std::string out = "'";
    for (char c : s) {
        out += c;
        if (c == '\'') out += '\'';
    }
    return out + "'";
}

// the sweep's data file, relative to the report folder
std::string data_file(const Sweep& sw) { return (fs::path("data") / (sw.id + ".dat")).string(); }

// one sweep's series on a Pareto plot: its points (errors of 0, a converged reference, cannot sit
// on a log axis) and their knob labels
// (a float twin's labels go below its points, the double's above)
std::string plot_series(const Sweep& sw, int point_type) {
    const char* label_offset = sw.precision == "float" ? "1.5,-0.8" : "1.5,0.8";
    return gp_quote(data_file(sw)) + " using 3:($2 > 0 ? $2 : 1/0) with linespoints pt " +
           std::to_string(point_type) + " ps 1.5 title " +
           gp_quote(sw.precision + " state, " + sw.knob) + ", \\\n     " + gp_quote(data_file(sw)) +
           " using 3:($2 > 0 ? $2 : 1/0):(sprintf('%g', $1)) with labels offset " + label_offset +
           " notitle";
}

// the Pareto plot of a sweep, with its float twin's series beside it when there is one
std::string gnuplot_script(const Sweep& sw, const Sweep* float_twin, const std::string& png) {
    std::ostringstream os;
    os << "# Pareto plot of the sweep " << sw.id
       << (float_twin ? " and " + float_twin->id : std::string())
       << ": error against wall time, each point labelled with its knob.\n"
       << "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
       << "    set terminal pngcairo noenhanced size 900,600\n"
       << "} else {\n"
       << "    set terminal png noenhanced size 900,600\n"
       << "}\n"
       << "set output " << gp_quote(png) << "\n"
       << "set title " << gp_quote(sw.title) << "\n"
       << "set xlabel 'wall time [s]'\n"
       << "set ylabel " << gp_quote(sw.error_measure) << "\n"
       << "set logscale xy\n"
       << "set format y '%.0e'\n"
       << "set grid\n"
       << "set key top right\n"
       << "set offsets graph 0.05, graph 0.15, graph 0.1, graph 0.1\n"
       << "plot " << plot_series(sw, 7);
    if (float_twin) os << ", \\\n     " << plot_series(*float_twin, 5);
    os << "\n";
    return os.str();
}

bool has_gnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

std::string sci(Real v) {
    if (!std::isfinite(v)) return v > 0 ? "inf" : (v < 0 ? "-inf" : "nan");
    return format("%.3g", v);
}

std::string table_cell(std::string s) {
    for (size_t i = 0; (i = s.find('|', i)) != std::string::npos; i += 2) s.replace(i, 1, "\\|");
    return s;
}

// the id of a float sweep's double twin
std::string double_twin_id(const Sweep& sw) {
    const std::string suffix = kFloatSweepSuffix;
    const bool has_suffix = sw.id.size() > suffix.size() &&
                            sw.id.compare(sw.id.size() - suffix.size(), suffix.size(), suffix) == 0;
    return has_suffix ? sw.id.substr(0, sw.id.size() - suffix.size()) : sw.id;
}

// the error at cap 5 of a CG sweep, NaN if absent
Real error_at_cap5(const Sweep& sw) {
    for (const SweepPoint& p : sw.points)
        if (p.knob == 5) return p.error;
    return std::nan("");
}

// The stability matrix: how its cases run and are judged, and one row per case.
void write_stability_section(std::ostream& md, const ReportContent& c) {
    md << "## Stability matrix\n\n"
       << "Each case runs in its own process on one thread (the scenes are small; under a loaded machine "
          "OpenMP barriers only add noise), bounded by "
       << stability_limits(c.scale).max_steps << " substeps and "
       << format("%.0f", stability_limits(c.scale).max_wall_s)
       << " s of wall time (plus 30 s grace before the process is killed). Energy = kinetic + gravitational "
          "(from the ground) + Neo-Hookean elastic; drift = (E_end - E_0)/E_scale and growth = (max E - E_0)/E_scale "
          "with E_scale the largest |E| seen. Moisture cases change the particle masses, so their energy is not "
          "conserved even by an exact integrator. Sticky ground impacts dissipate energy (negative drift). A substep "
          "that fails its checks (J <= 0, a non-finite state, more than 2 cells in one step) is rolled back and "
          "redone at half the time step, as mc-sim does (sim/mpm/step_retry.h); `retries` counts them, and a case "
          "stops with an error only when the step would fall below 1/"
       << (1 << RetryPolicy{}.max_halvings) << " of the stable one.\n\n"
       << "| case | group | setup | outcome | steps | retries | sim time [s] | max abs v [m/s] | energy drift "
          "| energy growth | wall [s] | message |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (size_t i = 0; i < c.stability.size(); ++i) {
        const StabilityResult& r = c.stability[i];
        const StabilityCase* info = i < c.cases.size() ? &c.cases[i] : nullptr;
        const bool ran = r.outcome == Outcome::Completed ||
                         r.outcome == Outcome::StoppedWithError ||
                         r.outcome == Outcome::SilentNaN || r.outcome == Outcome::Diverged;
        md << "| " << r.name << " | " << (info ? info->group : "") << " | "
           << table_cell(info ? info->description : "") << " | " << outcome_name(r.outcome) << " | "
           << r.steps << " | " << r.retries << " | " << sci(r.sim_time) << " | "
           << (ran ? sci(r.max_speed) : "-") << " | " << (ran ? sci(r.energy_drift) : "-") << " | "
           << (ran ? sci(r.energy_growth) : "-") << " | " << format("%.2f", r.wall_s) << " | "
           << table_cell(r.message) << " |\n";
    }
}

}  // namespace

void write_text_file(const fs::path& path, const std::string& text) {
    const fs::path tmp = path.string() + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary);
        out << text;
        if (!out) throw RuntimeError(path.string() + ": cannot write");
    }
    fs::rename(tmp, path);
}

const Sweep* find_sweep(const std::vector<Sweep>& sweeps, const std::string& id) {
    for (const Sweep& sw : sweeps)
        if (sw.id == id) return &sw;
    return nullptr;
}

std::vector<Figure> write_figures(const fs::path& dir, const std::vector<Sweep>& sweeps) {
    fs::create_directories(dir / "data");
    fs::create_directories(dir / "plots");
    const bool can_plot = has_gnuplot();
    // every data file first: a figure draws its float twin's too
    for (const Sweep& sw : sweeps) {
        std::ostringstream dat;
        dat << "# " << sw.title << "\n# knob: " << sw.knob << "\n# error: " << sw.error_measure
            << "\n# knob error wall_s\n";
        for (const SweepPoint& p : sw.points)
            dat << format("%.10g %.10g %.6g\n", p.knob, p.error, p.wall_s);
        write_text_file(dir / data_file(sw), dat.str());
    }
    std::vector<Figure> figures;
    for (const Sweep& sw : sweeps) {
        // a float sweep is drawn on its double twin's figure
        if (sw.precision == "float" && find_sweep(sweeps, double_twin_id(sw))) continue;
        Figure f;
        f.sweep_id = sw.id;
        f.script = fs::path("plots") / (sw.id + ".gp");
        f.png = sw.id + ".png";
        write_text_file(
            dir / f.script,
            gnuplot_script(sw, find_sweep(sweeps, sw.id + kFloatSweepSuffix), f.png.string()));
        f.command = "gnuplot " + f.script.string();
        if (can_plot) {
            const std::string cmd = "cd '" + dir.string() + "' && " + f.command + " 2>&1";
            f.is_made = std::system(cmd.c_str()) == 0 && fs::exists(dir / f.png);
        }
        figures.push_back(f);
    }
    return figures;
}

std::string report_markdown(const ReportContent& c, const std::vector<Figure>& figures) {
    std::ostringstream md;
    const bool full = c.scale == Scale::Full;
    md << "# mudcrack: error against run time, and stability on stiff and extreme cases\n\n"
       << "Generated by `" << c.command << "` (" << (full ? "full" : "reduced, --quick")
       << " scale, " << c.threads << " threads).\n\n"
       << "| | |\n|---|---|\n"
       << "| machine | " << c.machine.cpu_model << " |\n"
       << "| cores | " << c.machine.cores << " |\n"
       << "| memory | " << format("%.1f GiB", c.machine.memory_gib) << " |\n"
       << "| load average at start (1, 5, 15 min) | " << c.machine.load_average << " |\n"
       << "| commit | " << c.machine.commit << " |\n"
       << "| wall time, accuracy sweeps | " << format("%.1f s", c.accuracy_wall_s) << " |\n"
       << "| wall time, stability matrix | " << format("%.1f s", c.stability_wall_s) << " |\n"
       << "| wall time, whole report | " << format("%.1f s", c.total_wall_s) << " |\n\n";

    // summary
    int failures = 0, diverged = 0;
    for (const StabilityResult& r : c.stability) {
        failures += is_product_failure(r.outcome);
        diverged += r.outcome == Outcome::Diverged;
    }
    md << "## Summary\n\n"
       << "Fitted order = least-squares slope of log(error) against log(knob) over all points of the sweep.\n\n"
       << "| sweep | knob | points | fitted order | how to read it |\n|---|---|---|---|---|\n";
    for (const Sweep& sw : c.sweeps)
        md << "| [" << table_cell(sw.title) << "](#" << sw.id << ") | " << sw.knob << " | "
           << sw.points.size() << " | " << format("%.2f", sw.order) << " | "
           << table_cell(sw.order_note) << " |\n";
    md << "\nStability matrix: " << c.stability.size() << " cases, " << failures
       << " failures of the product (silent NaN, hang or crash), " << diverged
       << " diverged without an error (finite state, but energy non-finite or grown more than "
       << kDivergedEnergyGrowth << "x: flagged for the simulation's owners, see the table).\n\n";

    // the paper's CG claim
    md << "### The paper's claim: 5 CG iterations suffice\n\n"
       << "Criterion: RMS theta difference from the converged solve below "
       << sci(kCgClaimTolerance) << " of eta after the run.\n\n";
    for (const Sweep& sw : c.sweeps) {
        if (sw.id.rfind("cg_caps", 0) != 0) continue;
        const Real e5 = error_at_cap5(sw);
        md << "- " << sw.title << ": error at cap 5 = " << sci(e5) << " -> "
           << (e5 < kCgClaimTolerance ? "**holds**" : "**does not hold**") << "\n";
    }
    md << "\n";

    // sweeps
    md << "## Accuracy against analytic solutions\n\n"
       << "Each figure is a Pareto plot (error against wall time); pick the cheapest point below the error you "
          "need. Data in `data/<id>.dat`, script in `plots/<id>.gp`; every figure is made by running its command "
          "in this folder after `"
       << c.command << "` wrote the data.\n\n";
    for (size_t i = 0; i < c.sweeps.size(); ++i) {
        const Sweep& sw = c.sweeps[i];
        // a sweep's figure follows its float twin's table when the twin comes next (it holds both)
        const bool twin_is_next =
            i + 1 < c.sweeps.size() && c.sweeps[i + 1].id == sw.id + kFloatSweepSuffix;
        const Figure* fig = nullptr;
        for (const Figure& f : figures)
            if (f.sweep_id == double_twin_id(sw) && !twin_is_next) fig = &f;
        md << "### " << sw.title << " <a name=\"" << sw.id << "\"></a>\n\n"
           << "Error: " << sw.error_measure << ". Fitted order: **" << format("%.2f", sw.order)
           << "** (" << sw.order_note << ").\n\n"
           << "| " << sw.knob << " | error | wall [s] | notes |\n|---|---|---|---|\n";
        for (const SweepPoint& p : sw.points)
            md << "| " << format("%g", p.knob) << " | " << sci(p.error) << " | "
               << format("%.2f", p.wall_s) << " | " << table_cell(p.note) << " |\n";
        md << "\n";
        if (fig) {
            if (fig->is_made)
                md << "![" << sw.id << "](" << fig->png.string() << ")\n\n";
            else
                md << "(no PNG: gnuplot was not found or failed)\n\n";
            md << "Figure command: `" << fig->command << "`\n\n";
        }
    }

    write_stability_section(md, c);
    md << "\nOne case alone: `mc-report --case <name>" << (full ? "" : " --quick")
       << "` (prints its result line).\n";
    return md.str();
}

}  // namespace mudcrack::report
