#include "sim/core/stats.h"

#include <sys/resource.h>

namespace mudcrack {

int64_t peak_rss_bytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return int64_t(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

}  // namespace mudcrack
