#include "sim/model.h"

#include <cmath>

namespace mudcrack {

Real ElasticParams::wave_speed() const { return std::sqrt((lambda() + 2 * mu()) / density); }

Real elastic_dt_bound(const SimModel& model) {
    return model.time.cfl_elastic * model.h / model.elastic.wave_speed();
}

}  // namespace mudcrack
