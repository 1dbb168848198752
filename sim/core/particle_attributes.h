#pragma once
/// The per-particle attributes a frame cache can carry, listed once. The list drives
/// ParticleFrame's arrays, CacheAttributes' flags, the VDB points writer and reader, the shot's
/// /derived/cache entries and derive_cache. Adding a cached attribute is one MC_CACHED_ATTRIBUTES
/// entry plus its value in sim/mpm/cached_values.h (the physics that computes it from the state).
#include <cstddef>
#include <type_traits>

#include "sim/core/types.h"

namespace mudcrack {

using Mat3f = Eigen::Matrix<float, 3, 3>;

/// Which physics a shot needs for an attribute to exist (derive_cache's test).
enum class CachePhysics {
    Always,      // every shot
    Moisture,    // a /moisture section
    Plasticity,  // a /plasticity section
    Damage,      // plasticity with /plasticity/damage_strain
    Surfacing,   // a /surfacing section (what only the surfacing reads)
};

/// When a shot with the physics caches the attribute.
enum class CachePolicy {
    ByPhysics,  // always, when the shot has the physics; listed in /derived/cache as true or false
    OnRequest,  // only when the shot sets /sim/cache/<key>; listed in /derived/cache only then,
                // so adding one leaves every other shot's sim slice (and make's target) unchanged
};

// X(type, frame member, shot key, VDB attribute name, physics, policy, doc), in the VDB file's
// attribute order (within each of float, vector and matrix). type: float, Vec3f or Mat3f.
#define MC_CACHED_ATTRIBUTES(X)                                                                   \
    X(Vec3f, v, velocity, "v", Always, ByPhysics, "velocity [m/s]")                               \
    X(float, theta, theta, "theta", Moisture, ByPhysics, "volumetric water content in [0, eta]")  \
    X(float, saturation, saturation, "saturation", Moisture, ByPhysics, "s = theta/eta in [0,1]") \
    X(float, alpha, alpha, "alpha", Plasticity, ByPhysics,                                        \
      "NACC hardening state (log Jp plus eps log Jw)")                                            \
    X(float, Jw, Jw, "Jw", Moisture, ByPhysics, "pore deformation determinant, 1 - eta (1 - s)")  \
    X(Mat3f, Fe, Fe, "Fe", Surfacing, ByPhysics,                                                  \
      "elastic deformation gradient (the core rotation of Eq. 13)")                               \
    X(float, damage, damage, "damage", Damage, OnRequest,                                         \
      "tensile damage d in [0, 1]: where the soil tore")

/// How an attribute is stored: one float, a vector or a matrix per particle.
enum class AttributeKind { Float, Vector, Matrix };

template <class T>
constexpr AttributeKind attribute_kind() {
    static_assert(std::is_same_v<T, float> || std::is_same_v<T, Vec3f> || std::is_same_v<T, Mat3f>,
                  "a cached attribute is a float, Vec3f or Mat3f");
    if constexpr (std::is_same_v<T, float>)
        return AttributeKind::Float;
    else if constexpr (std::is_same_v<T, Vec3f>)
        return AttributeKind::Vector;
    else
        return AttributeKind::Matrix;
}

/// One row of MC_CACHED_ATTRIBUTES, for code that iterates at run time.
struct CachedAttributeInfo {
    const char* shot_key;  // /derived/cache and /sim/cache key
    const char* vdb_name;  // attribute name in the frame caches
    AttributeKind kind;
    CachePhysics physics;
    CachePolicy policy;
    const char* doc;
};

inline constexpr CachedAttributeInfo kCachedAttributes[] = {
#define MC_CACHED_ATTRIBUTE_INFO(T, member, key, vdb, physics, policy, doc) \
    {#key, vdb, attribute_kind<T>(), CachePhysics::physics, CachePolicy::policy, doc},
    MC_CACHED_ATTRIBUTES(MC_CACHED_ATTRIBUTE_INFO)
#undef MC_CACHED_ATTRIBUTE_INFO
};

inline constexpr size_t kCachedAttributeCount = std::size(kCachedAttributes);

/// Which per-particle attributes the frame caches carry (what later stages need); by default
/// those every shot has (the velocity).
struct CacheAttributes {
#define MC_CACHE_FLAG(T, member, key, vdb, physics, policy, doc) \
    bool key = CachePhysics::physics == CachePhysics::Always;
    MC_CACHED_ATTRIBUTES(MC_CACHE_FLAG)
#undef MC_CACHE_FLAG

    /// The flag of the i-th table row.
    bool& operator[](size_t i) { return *flags()[i]; }
    bool operator[](size_t i) const { return *const_cast<CacheAttributes*>(this)->flags()[i]; }

private:
    struct Flags {
        bool* p[kCachedAttributeCount];
        bool* operator[](size_t i) const { return p[i]; }
    };
    Flags flags() {
#define MC_CACHE_FLAG_PTR(T, member, key, vdb, physics, policy, doc) &key,
        return Flags{{MC_CACHED_ATTRIBUTES(MC_CACHE_FLAG_PTR)}};
#undef MC_CACHE_FLAG_PTR
    }
};

}  // namespace mudcrack
