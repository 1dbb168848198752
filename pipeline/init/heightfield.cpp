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

TetMesh make_heightfield_tets(const HeightfieldSource& hf) {
    if (!(hf.size.x() > 0) || !(hf.size.z() > 0))
        throw ShotValueError("/source/heightfield/size = [" + num(hf.size.x()) + ", " +
                             num(hf.size.z()) + "]: both extents must be > 0 [m]");
    if (!(hf.spacing > 0))
        throw ShotValueError("/source/heightfield/spacing = " + num(hf.spacing) +
                             ": must be > 0 [m]");
    const Real x0 = -0.5 * hf.size.x(), z0 = -0.5 * hf.size.z();
    const double columns_x = lattice_cells(hf.size.x(), hf.spacing);
    const double columns_z = lattice_cells(hf.size.z(), hf.spacing);
    if ((columns_x + 1) * (columns_z + 1) > kMaxInitParticles)
        throw ShotValueError("/source/heightfield/spacing = " + num(hf.spacing) + ": gives " +
                             count_text((columns_x + 1) * (columns_z + 1)) +
                             " columns; expected at most " + count_text(kMaxInitParticles) +
                             ": raise the spacing");
    const int nx = int(columns_x), nz = int(columns_z);

    // the top height per column
    std::vector<Real> top(static_cast<size_t>(nx + 1) * (nz + 1));
    auto column_x = [&](int i) { return x0 + hf.size.x() * i / nx; };
    auto column_z = [&](int k) { return z0 + hf.size.z() * k / nz; };
    if (hf.image.empty()) {
        if (!(hf.channel_depth + hf.amplitude < hf.base))
            throw ShotValueError(
                "/source/heightfield: channel_depth (" + num(hf.channel_depth) + ") + amplitude (" +
                num(hf.amplitude) + ") >= base (" + num(hf.base) +
                "): the channel would cut through the floor; expected their sum < base [m]");
        for (int k = 0; k <= nz; ++k)
            for (int i = 0; i <= nx; ++i)
                top[i + (nx + 1) * k] = riverbed_height(hf, column_x(i), column_z(k));
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
                top[i + (nx + 1) * k] = h;
            }
        if (raised > 0)
            log::warn("heightfield-floor", hf.image + ": " + std::to_string(raised) +
                                               " dark columns raised to the minimum thickness " +
                                               num(floor_height) + " m (a quarter of the spacing)");
    }
    const Real tallest = *std::max_element(top.begin(), top.end());
    // a double until it is bounded: a tall column over a fine spacing has more layers than an int
    // holds
    const double layers = std::max(1.0, std::ceil(tallest / hf.spacing - 1e-9));
    const double points = double(nx + 1) * (layers + 1) * (nz + 1);
    if (points > kMaxInitParticles)
        throw ShotValueError("/source/heightfield/spacing = " + num(hf.spacing) + ": gives " +
                             count_text(points) + " particles; expected at most " +
                             count_text(kMaxInitParticles) + ": raise the spacing");
    const int ny = int(layers);

    return make_column_lattice_tets(x0, z0, hf.size.x(), hf.size.z(), nx, ny, nz, top);
}

}  // namespace mudcrack
