#include "pipeline/resolution.h"
#include "core/film.h"
#include <algorithm>
#include <charconv>
#include <stdexcept>

namespace lpt::pipeline {

std::optional<std::vector<int>> split_integers(const std::string& text, char sep) {
    std::vector<int> values;
    size_t start = 0;
    while (true) {
        const size_t end = std::min(text.find(sep, start), text.size());
        const char *first = text.data() + start, *last = text.data() + end;
        int v = 0;
        const auto [at, error] = std::from_chars(first, last, v);
        // from_chars takes a leading '-': a range's pieces are counts and indices, never negative
        if (first == last || *first == '-' || error != std::errc() || at != last) return std::nullopt;
        values.push_back(v);
        if (end == text.size()) return values;
        start = end + 1;
    }
}

void parse_resolution(const std::string& text, int& w, int& h, const std::string& option) {
    std::string lower = text;
    for (char& c : lower)
        if (c == 'X') c = 'x';
    const std::optional<std::vector<int>> v = split_integers(lower, 'x');
    if (!v || v->size() != 2 || (*v)[0] < 1 || (*v)[1] < 1)
        throw std::invalid_argument(option + " expects WxH with positive integers, got '" + text + "'");
    w = (*v)[0];
    h = (*v)[1];
}

void check_size_fits(int w, int h, size_t floats_per_pixel, const std::string& option) {
    try {
        check_image_fits(w, h, floats_per_pixel);
    } catch (const std::length_error& e) {
        throw std::invalid_argument(option + ": " + e.what());
    }
}

}  // namespace lpt::pipeline
