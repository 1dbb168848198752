#include "pipeline/stages/sim/sim_checkpoint.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <regex>
#include <string>
#include <type_traits>

#include "pipeline/io/checkpoint_io.h"
#include "sim/core/error.h"

namespace fs = std::filesystem;

namespace mudcrack {
namespace {

// bump when the set or meaning of the saved arrays changes; a reader refuses other versions
// 2: strength and damage arrays; 3: the moisture flux history
constexpr int64_t kSimCheckpointVersion = 3;

// the elements' entries as doubles (a float's exactly): a restored state is bitwise the saved one
template <class Element>
std::vector<double> flatten(const std::vector<Element>& values) {
    using C = PackedNumbers<Element>;
    std::vector<double> flat(values.size() * C::kCount);
    const auto* entries = reinterpret_cast<const typename C::Scalar*>(values.data());
    for (size_t i = 0; i < flat.size(); ++i) flat[i] = static_cast<double>(entries[i]);
    return flat;
}

// the named array as n elements of `Element` (n = 0 accepted for optional arrays); a float
// array's doubles must each be a float
template <class Element>
std::vector<Element> unflatten(const Checkpoint& c, const std::string& name, size_t n,
                               bool is_optional) {
    using C = PackedNumbers<Element>;
    using Scalar = typename C::Scalar;
    const std::vector<double>& flat = is_optional && c.f64.count(name) && c.f64.at(name).empty()
                                          ? c.f64.at(name)
                                          : c.require_f64(name, n * C::kCount);
    std::vector<Element> values(flat.size() / C::kCount);
    auto* entries = reinterpret_cast<Scalar*>(values.data());
    for (size_t i = 0; i < flat.size(); ++i) {
        entries[i] = static_cast<Scalar>(flat[i]);
        if (static_cast<double>(entries[i]) != flat[i] && !std::isnan(flat[i]))
            throw InputError(c.source + ": " + name + "[" + std::to_string(i) +
                             "] = " + std::to_string(flat[i]) +
                             ": not a float, but the checkpoint holds a float state");
    }
    return values;
}

void save_array(Checkpoint& c, const char* name, const std::vector<int32_t>& values) {
    c.i32[name] = values;
}

template <class Element>
void save_array(Checkpoint& c, const char* name, const std::vector<Element>& values) {
    c.f64[name] = flatten(values);
}

void load_array(const Checkpoint& c, const char* name, size_t n, ArrayPresence presence,
                std::vector<int32_t>& values) {
    const bool is_empty_optional =
        presence == ArrayPresence::Optional && c.i32.count(name) && c.i32.at(name).empty();
    values = is_empty_optional ? std::vector<int32_t>{} : c.require_i32(name, n);
}

template <class Element>
void load_array(const Checkpoint& c, const char* name, size_t n, ArrayPresence presence,
                std::vector<Element>& values) {
    values = unflatten<Element>(c, name, n, presence == ArrayPresence::Optional);
}

// the run's counters (MC_SIM_TOTALS): int64 counters as meta_int, the others as meta_double
enum class TotalPresence { Required, Optional };
void save_total(Checkpoint& c, const std::string& key, int64_t value) { c.meta_int[key] = value; }
void save_total(Checkpoint& c, const std::string& key, double value) { c.meta_double[key] = value; }
// an Optional counter an older checkpoint lacks is 0: that run never counted it
void load_total(const Checkpoint& c, const std::string& key, TotalPresence presence,
                int64_t& value) {
    value = presence == TotalPresence::Optional && !c.meta_int.count(key) ? 0 : c.require_int(key);
}
void load_total(const Checkpoint& c, const std::string& key, TotalPresence presence,
                double& value) {
    value = presence == TotalPresence::Optional && !c.meta_double.count(key)
                ? 0
                : c.require_double(key);
}

}  // namespace

fs::path checkpoint_path(const fs::path& dir, int frame) {
    char name[64];
    std::snprintf(name, sizeof name, "checkpoint.%04d.bin", frame);
    return dir / name;
}

std::vector<int> list_checkpoint_frames(const fs::path& dir) {
    static const std::regex pattern(R"(^checkpoint\.(\d+)\.bin$)");
    std::vector<int> frames;
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
        std::smatch m;
        const std::string name = entry.path().filename().string();
        if (std::regex_match(name, m, pattern)) frames.push_back(std::stoi(m[1]));
    }
    std::sort(frames.begin(), frames.end());
    return frames;
}

template <class S>
void write_sim_checkpoint(const fs::path& path, const SimCheckpointOf<S>& checkpoint) {
    const SimStateOf<S>& s = checkpoint.state;
    const SimTotals& t = checkpoint.totals;
    Checkpoint c;
    // identity: what wrote it, for which shot slice, at which frame
    c.meta_string["stage"] = "sim";
    c.meta_int["sim_checkpoint_version"] = kSimCheckpointVersion;
    c.meta_string["slice_hash"] = checkpoint.slice_hash;
    c.meta_int["frame"] = checkpoint.frame;
    c.meta_int["threads"] = checkpoint.threads;
    c.meta_string["precision"] = state_precision_name<S>();
    // the state, slot order included (id maps slots to particles)
    c.meta_double["time"] = s.time;
    c.meta_int["step_count"] = s.step_count;
    c.meta_double["moisture_lag"] = s.moisture_lag;
    c.meta_int["particles"] = int64_t(s.size());
    s.for_each_array(
        [&](const char* name, const auto& array, ArrayPresence) { save_array(c, name, array); });
    // the moisture CG's flux history (block keys as int64: they are uint32)
    c.meta_int["moisture_flux.count"] = s.moisture_flux.count;
    c.meta_double["moisture_flux.dt"] = s.moisture_flux.dt;
    c.meta_double["moisture_flux.dt_prev"] = s.moisture_flux.dt_prev;
    c.i64["moisture_flux.keys"].assign(s.moisture_flux.keys.begin(), s.moisture_flux.keys.end());
    c.f64["moisture_flux.flux"] = s.moisture_flux.flux;
    c.f64["moisture_flux.flux_prev"] = s.moisture_flux.flux_prev;
    c.f64["domain_min"] = flatten(std::vector<Vec3>{s.domain_min});
    c.f64["domain_max"] = flatten(std::vector<Vec3>{s.domain_max});
    // the run's counters, so a resumed run's manifest covers every frame
#define MC_SAVE_TOTAL(type, name, presence) save_total(c, "totals." #name, t.name);
    MC_SIM_TOTALS(MC_SAVE_TOTAL)
#undef MC_SAVE_TOTAL
    // the frame caches' checksums, as numbers (a CRC-32 fits an int64)
    for (const auto& [frame, crc] : checkpoint.cache_crc32) {
        c.i64["caches.frame"].push_back(frame);
        c.i64["caches.crc32"].push_back(int64_t(std::stoull(crc, nullptr, 16)));
    }
    write_checkpoint(path, c);
}

template <class S>
SimCheckpointOf<S> read_sim_checkpoint(const fs::path& path) {
    const Checkpoint c = read_checkpoint(path);
    if (c.meta_string.count("stage") == 0 || c.meta_string.at("stage") != "sim")
        throw InputError(path.string() + ": not a simulation checkpoint (no stage = \"sim\")");
    const int64_t version = c.require_int("sim_checkpoint_version");
    if (version != kSimCheckpointVersion)
        throw InputError(path.string() + ": sim_checkpoint_version = " + std::to_string(version) +
                         ": this build reads version " + std::to_string(kSimCheckpointVersion));
    const int64_t n_signed = c.require_int("particles");
    if (n_signed < 0)
        throw InputError(path.string() + ": particles = " + std::to_string(n_signed) +
                         ": expected >= 0");
    const size_t n = size_t(n_signed);
    // written before the key existed: double
    const std::string precision =
        c.meta_string.count("precision") ? c.meta_string.at("precision") : "double";
    if (precision != state_precision_name<S>())
        throw InputError(path.string() + ": precision = \"" + precision + "\": this run keeps a " +
                         state_precision_name<S>() +
                         " state (/sim/precision); the checkpoint is not used");

    SimCheckpointOf<S> sc;
    sc.frame = int(c.require_int("frame"));
    sc.slice_hash = c.require_string("slice_hash");
    sc.threads = int(c.require_int("threads"));
    SimStateOf<S>& s = sc.state;
    s.time = c.require_double("time");
    s.step_count = c.require_int("step_count");
    // written before the key existed: every step solved its moisture, so none was owed
    s.moisture_lag = c.meta_double.count("moisture_lag") ? c.meta_double.at("moisture_lag") : 0;
    s.for_each_array([&](const char* name, auto& array, ArrayPresence presence) {
        load_array(c, name, n, presence, array);
    });
    MoistureFluxHistory& h = s.moisture_flux;
    h.count = int(c.require_int("moisture_flux.count"));
    h.dt = c.require_double("moisture_flux.dt");
    h.dt_prev = c.require_double("moisture_flux.dt_prev");
    const std::vector<int64_t>& keys = c.require_i64("moisture_flux.keys");
    h.keys.assign(keys.begin(), keys.end());
    h.flux = c.require_f64("moisture_flux.flux", keys.size() * mpm::kBlockNodes);
    h.flux_prev = c.require_f64("moisture_flux.flux_prev", keys.size() * mpm::kBlockNodes);
    if (h.count < 0 || h.count > 2)
        throw InputError(path.string() + ": moisture_flux.count = " + std::to_string(h.count) +
                         ": expected 0, 1 or 2");
    s.domain_min = unflatten<Vec3>(c, "domain_min", 1, false)[0];
    s.domain_max = unflatten<Vec3>(c, "domain_max", 1, false)[0];
    SimTotals& t = sc.totals;
#define MC_LOAD_TOTAL(type, name, presence) \
    load_total(c, "totals." #name, TotalPresence::presence, t.name);
    MC_SIM_TOTALS(MC_LOAD_TOTAL)
#undef MC_LOAD_TOTAL
    // none recorded (no cache written yet, or an older checkpoint): no frame it precedes is trusted
    if (c.i64.count("caches.frame")) {
        const std::vector<int64_t>& frames = c.require_i64("caches.frame");
        const std::vector<int64_t>& crcs = c.require_i64("caches.crc32", frames.size());
        for (size_t i = 0; i < frames.size(); ++i) {
            char hex[16];
            std::snprintf(hex, sizeof hex, "%08llx",
                          static_cast<unsigned long long>(crcs[i]) & 0xffffffffULL);
            sc.cache_crc32[int(frames[i])] = hex;
        }
    }
    return sc;
}

template void write_sim_checkpoint(const fs::path&, const SimCheckpointOf<double>&);
template void write_sim_checkpoint(const fs::path&, const SimCheckpointOf<float>&);
template SimCheckpointOf<double> read_sim_checkpoint(const fs::path&);
template SimCheckpointOf<float> read_sim_checkpoint(const fs::path&);

}  // namespace mudcrack
