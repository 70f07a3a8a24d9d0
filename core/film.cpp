#include "core/film.h"
#include <cstdio>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace lpt {

namespace {

double physical_memory_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
}

std::string gib(double bytes) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / double(1ull << 30));
    return buf;
}

}  // namespace

void check_image_fits(int width, int height, size_t floats_per_pixel) {
    const std::string size = std::to_string(width) + "x" + std::to_string(height);
    if (width < 1 || height < 1) throw std::length_error("an image of " + size + " pixels: both sides must be >= 1");
    const double need = double(width) * double(height) * double(floats_per_pixel) * sizeof(float);
    const double have = physical_memory_bytes();
    if (have > 0 && need > have)
        throw std::length_error("an image of " + size + " pixels needs " + gib(need) + ", more than this machine's " +
                                gib(have) + " of memory");
}

}  // namespace lpt
