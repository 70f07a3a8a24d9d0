#include "pipeline/resolution.h"
#include <cstdio>
#include <stdexcept>

namespace lpt::pipeline {

void parse_resolution(const std::string& text, int& w, int& h, const std::string& option) {
    char x = 0;
    int a = 0, b = 0;
    if (std::sscanf(text.c_str(), "%d%c%d", &a, &x, &b) != 3 || (x != 'x' && x != 'X') || a < 1 || b < 1)
        throw std::invalid_argument(option + " expects WxH with positive integers, got '" + text + "'");
    w = a;
    h = b;
}

}  // namespace lpt::pipeline
