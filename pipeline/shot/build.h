#pragma once
/// Typed stage parameters from a checked, default-filled shot tree (validate.h), with the checks
/// that involve more than one key. Each builder writes the values it derives back into the tree
/// (resolved paths, beta0/beta1, theta_init), so the slices record what the stages will run with.
/// Internal to pipeline/shot.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "pipeline/init/init_params.h"
#include "pipeline/shot/validate.h"
#include "render/render_params.h"
#include "sim/model.h"
#include "surfacing/surface_params.h"

namespace mudcrack::spec {

/// /reuse: the other shot of this folder whose matching stages make shares ("" when unset).
/// Checks it names an existing shot file other than this one that does not reuse a third.
std::string build_reuse(const nlohmann::json& tree, const std::string& shot_path, Issues& issues);

/// /source and /init. Resolves paths against the folder of `shot_path` and checks the files
/// exist; checks box extents and the heightfield channel. Drops the unselected /source/<type>
/// sections from `tree`.
InitParams build_init(nlohmann::json& tree, const std::string& shot_path, Issues& issues);

/// /material, /plasticity, /moisture, /sim, /frames, /colliders, /source/initial_velocity.
/// Refuses a fixed /sim/dt above the elastic bound, theta_init outside [0, eta], empty boxes
/// and frame ranges. The cache attributes are left at their defaults (see derive_cache).
SimModel build_sim(nlohmann::json& tree, Issues& issues);

/// /surfacing, or nullopt when the section is off; adds an issue for debris asked of a mode that
/// has none.
std::optional<SurfaceParams> build_surface(const nlohmann::json& tree, Issues& issues);

/// /render, or nullopt when the section is off.
std::optional<RenderParams> build_render(const nlohmann::json& tree);

/// What the frame caches carry (MC_CACHED_ATTRIBUTES): each attribute the shot's physics has,
/// velocity always; theta, saturation and Jw with moisture; alpha with plasticity; Fe when the
/// shot surfaces (only the surfacing reads it, and it is 9 floats a particle); and an on-request
/// attribute only when /sim/cache/<key> asks for it (an error without its physics). Never what a
/// render draws: a render key must not change the sim's slice, or editing it would re-simulate.
CacheAttributes derive_cache(const nlohmann::json& tree, const SimModel& sim,
                             const std::optional<SurfaceParams>& surface, Issues& issues);

/// Checks between sections: the box source inside the domain, the ground inside the domain, the
/// turntable frame inside the frame range.
void check_across(const nlohmann::json& tree, const InitParams& init, const SimModel& sim,
                  const std::optional<RenderParams>& render, Issues& issues);

/// Physical plausibility, naming the key each refusal blames (pipeline/shot/plausibility.cpp):
/// the time step the shot starts with (the fixed or largest step, the elastic bound, the
/// velocity bound with the initial velocity and one frame of gravity) against mc-sim's floor
/// of kCollapsedDtFraction frame lengths and against kMaxSubstepsPerFrame substeps a frame, naming
/// the Poisson ratio too where it sets the wave speed; /sim/h against OpenVDB's smallest voxel,
/// against the body (at least one cell across its thinnest side), against a given domain (at least
/// a cell, with /colliders/domain/padding leaving a free cell between its walls) and against the
/// domain (the grid's block count); /colliders/ground/height below the body's top and, where the
/// body's bottom is known, within what the body falls in the shot; a lattice source's particle
/// count against the machine's memory; /render/resolution x /render/samples against what OSMesa
/// allocates; a camera placed by hand: finite in the renderer's single precision and away from its
/// target.
void check_plausible(const nlohmann::json& tree, const InitParams& init, const SimModel& sim,
                     const std::optional<RenderParams>& render, Issues& issues);

/// Warnings for valid but doubtful settings: zeta below the bound of docs/physics.md §5.5, under
/// which intact dried material breaks spuriously.
void warn_doubtful(const SimModel& sim, const std::optional<SurfaceParams>& surface,
                   const std::string& shot_path);

}  // namespace mudcrack::spec
