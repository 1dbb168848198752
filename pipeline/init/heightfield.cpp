#include "pipeline/init/heightfield.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pipeline/init/lattice.h"
#include "pipeline/io/image_io.h"
#include "sim/core/error.h"
#include "sim/core/log.h"

namespace mudcrack {
namespace {

constexpr Real kTwoPi = 2 * kPi;

/// A grayscale image sampled bilinearly over the slab's footprint, in [0, 1].
class GrayImage {
public:
    explicit GrayImage(Image image) : m_image(std::move(image)) {}

    /// u, v in [0, 1]: u along the width (x), v along the height (z), top row at v = 0.
    Real sample(Real u, Real v) const {
        const Real fx = std::clamp(u, Real(0), Real(1)) * (m_image.width - 1);
        const Real fy = std::clamp(v, Real(0), Real(1)) * (m_image.height - 1);
        const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
        const int x1 = std::min(x0 + 1, m_image.width - 1),
                  y1 = std::min(y0 + 1, m_image.height - 1);
        const Real tx = fx - x0, ty = fy - y0;
        return (1 - ty) * ((1 - tx) * gray(x0, y0) + tx * gray(x1, y0)) +
               ty * ((1 - tx) * gray(x0, y1) + tx * gray(x1, y1));
    }

private:
    Real gray(int x, int y) const {
        const uint8_t* p =
            &m_image.pixels[(static_cast<size_t>(y) * m_image.width + x) * m_image.channels];
        // Rec. 709 luma for colour images
        const Real value =
            m_image.channels >= 3 ? 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] : p[0];
        return value / 255.0;
    }
    Image m_image;
};

std::string num(Real v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

}  // namespace

Real riverbed_height(const HeightfieldSource& hf, Real x, Real z) {
    const Real sx = hf.size.x(), sz = hf.size.z();
    // banks: two incommensurate sinusoids, each at most half the amplitude
    const Real undulation =
        0.5 * std::sin(kTwoPi * 1.3 * x / sx + 0.7) * std::cos(kTwoPi * 1.1 * z / sz + 0.3) +
        0.5 * std::sin(kTwoPi * 2.3 * (x + 0.6 * z) / sx + 1.9);
    // the channel: a cosine bowl around a sinusoidal centre line
    const Real d = z - hf.channel_meander * std::sin(kTwoPi * x / sx);
    const Real carve = std::abs(d) < 0.5 * hf.channel_width
                           ? 0.5 * hf.channel_depth * (1 + std::cos(kTwoPi * d / hf.channel_width))
                           : Real(0);
    return hf.base + hf.amplitude * undulation - carve;
}

namespace {

/// The top height of each column of the terrain: columns ~spacing apart over its footprint,
/// (nx + 1) x (nz + 1) of them, x fastest.
struct ColumnTops {
    Real x0 = 0, z0 = 0;  // the footprint's lower corner [m]
    Real sx = 0, sz = 0;  // the footprint's extent [m]
    int nx = 0, nz = 0;   // cells along x and z
    std::vector<Real> top;
    Real x(int i) const { return x0 + sx * i / nx; }
    Real z(int k) const { return z0 + sz * k / nz; }
    int32_t index(int i, int k) const { return i + (nx + 1) * k; }
};

ColumnTops column_tops(const HeightfieldSource& hf) {
    if (!(hf.size.x() > 0) || !(hf.size.z() > 0))
        throw ShotValueError("/source/heightfield/size = [" + num(hf.size.x()) + ", " +
                             num(hf.size.z()) + "]: both extents must be > 0 [m]");
    if (!(hf.spacing > 0))
        throw ShotValueError("/source/heightfield/spacing = " + num(hf.spacing) +
                             ": must be > 0 [m]");
    ColumnTops c;
    c.sx = hf.size.x();
    c.sz = hf.size.z();
    c.x0 = -0.5 * c.sx;
    c.z0 = -0.5 * c.sz;
    const double columns_x = lattice_cells(hf.size.x(), hf.spacing);
    const double columns_z = lattice_cells(hf.size.z(), hf.spacing);
    if ((columns_x + 1) * (columns_z + 1) > kMaxInitParticles)
        throw ShotValueError("/source/heightfield/spacing = " + num(hf.spacing) + ": gives " +
                             count_text((columns_x + 1) * (columns_z + 1)) +
                             " columns; expected at most " + count_text(kMaxInitParticles) +
                             ": raise the spacing");
    c.nx = int(columns_x);
    c.nz = int(columns_z);
    const int nx = c.nx, nz = c.nz;
    c.top.resize(static_cast<size_t>(nx + 1) * (nz + 1));
    if (hf.image.empty()) {
        if (!(hf.channel_depth + hf.amplitude < hf.base))
            throw ShotValueError(
                "/source/heightfield: channel_depth (" + num(hf.channel_depth) + ") + amplitude (" +
                num(hf.amplitude) + ") >= base (" + num(hf.base) +
                "): the channel would cut through the floor; expected their sum < base [m]");
        for (int k = 0; k <= nz; ++k)
            for (int i = 0; i <= nx; ++i)
                c.top[c.index(i, k)] = riverbed_height(hf, c.x(i), c.z(k));
    } else {
        const GrayImage image(read_png(hf.image));
        const Real floor_height = 0.25 * hf.spacing;
        int64_t raised = 0;
        for (int k = 0; k <= nz; ++k)
            for (int i = 0; i <= nx; ++i) {
                Real h = hf.image_height * image.sample(Real(i) / nx, Real(k) / nz);
                if (h < floor_height) {
                    h = floor_height;
                    ++raised;
                }
                c.top[c.index(i, k)] = h;
            }
        if (raised > 0)
            log::warn("heightfield-floor", hf.image + ": " + std::to_string(raised) +
                                               " dark columns raised to the minimum thickness " +
                                               num(floor_height) + " m (a quarter of the spacing)");
    }
    return c;
}

}  // namespace

TetMesh make_heightfield_tets(const HeightfieldSource& hf) {
    const ColumnTops c = column_tops(hf);
    const Real tallest = *std::max_element(c.top.begin(), c.top.end());
    // a double until it is bounded: a tall column over a fine spacing has more layers than an int
    // holds
    const double layers = std::max(1.0, std::ceil(tallest / hf.spacing - 1e-9));
    const double points = double(c.nx + 1) * (layers + 1) * (c.nz + 1);
    if (points > kMaxInitParticles)
        throw ShotValueError("/source/heightfield/spacing = " + num(hf.spacing) + ": gives " +
                             count_text(points) + " particles; expected at most " +
                             count_text(kMaxInitParticles) + ": raise the spacing");
    const int ny = int(layers);

    return make_column_lattice_tets(c.x0, c.z0, c.sx, c.sz, c.nx, ny, c.nz, c.top);
}

InputSurface heightfield_surface(const HeightfieldSource& hf) {
    const ColumnTops c = column_tops(hf);
    InputSurface s;
    const int32_t bottom = static_cast<int32_t>(c.top.size());  // the bottom's first id
    s.positions.reserve(2 * c.top.size());
    for (int k = 0; k <= c.nz; ++k)  // the top, ids c.index(i, k)
        for (int i = 0; i <= c.nx; ++i)
            s.positions.emplace_back(c.x(i), c.top[c.index(i, k)], c.z(k));
    for (int k = 0; k <= c.nz; ++k)  // the bottom, ids bottom + c.index(i, k)
        for (int i = 0; i <= c.nx; ++i) s.positions.emplace_back(c.x(i), 0, c.z(k));
    // a quad's two triangles, turned to face `outward` (every quad here is planar or nearly so,
    // and a heightfield's top never overhangs, so the sign of one normal decides)
    auto add_quad = [&](int32_t a, int32_t b, int32_t d, int32_t e, const Vec3& outward) {
        const Vec3& p = s.positions[a];
        if ((s.positions[b] - p).cross(s.positions[d] - p).dot(outward) < 0) std::swap(b, e);
        s.faces.push_back({a, b, d});
        s.faces.push_back({a, d, e});
    };
    for (int k = 0; k < c.nz; ++k)
        for (int i = 0; i < c.nx; ++i) {
            const int32_t q[4] = {c.index(i, k), c.index(i + 1, k), c.index(i + 1, k + 1),
                                  c.index(i, k + 1)};
            add_quad(q[0], q[1], q[2], q[3], Vec3::UnitY());
            add_quad(bottom + q[0], bottom + q[1], bottom + q[2], bottom + q[3], -Vec3::UnitY());
        }
    for (int i = 0; i < c.nx; ++i)  // the walls at z = z0 and z = z0 + size.z
        for (int k : {0, c.nz}) {
            const int32_t a = c.index(i, k), b = c.index(i + 1, k);
            add_quad(a, b, bottom + b, bottom + a, Vec3(0, 0, k == 0 ? -1 : 1));
        }
    for (int k = 0; k < c.nz; ++k)  // the walls at x = x0 and x = x0 + size.x
        for (int i : {0, c.nx}) {
            const int32_t a = c.index(i, k), b = c.index(i, k + 1);
            add_quad(a, b, bottom + b, bottom + a, Vec3(i == 0 ? -1 : 1, 0, 0));
        }
    return s;
}

}  // namespace mudcrack
