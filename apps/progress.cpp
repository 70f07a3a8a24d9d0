#include "apps/commands.h"
#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace lpt::app {

namespace {
double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
}  // namespace

void parse_resolution(const std::string& s, int& w, int& h) {
    char x = 0;
    int a = 0, b = 0;
    if (std::sscanf(s.c_str(), "%d%c%d", &a, &x, &b) != 3 || (x != 'x' && x != 'X') || a < 1 || b < 1)
        throw std::invalid_argument("--res expects WxH with positive integers, got '" + s + "'");
    w = a;
    h = b;
}

Progress::Progress(std::string label, bool enabled) : m_label(std::move(label)), m_enabled(enabled), m_start(now()) {}

void Progress::update(double fraction, uint64_t rays) {
    if (!m_enabled) return;
    double t = now();
    if (t - m_last < 0.25 && fraction < 1.0) return;
    m_last = t;
    double el = t - m_start;
    double eta = fraction > 0 ? el * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "\r[%s] %5.1f%% | %6.2f Mrays/s | elapsed %.1f s | ETA %.1f s   ", m_label.c_str(), 100.0 * fraction,
                 el > 0 ? rays / el * 1e-6 : 0.0, el, eta);
    std::fflush(stderr);
}

void Progress::finish(uint64_t rays) {
    if (!m_enabled) return;
    double el = now() - m_start;
    std::fprintf(stderr, "\r[%s] done in %.2f s | %.2f Mrays/s                              \n", m_label.c_str(), el, el > 0 ? rays / el * 1e-6 : 0.0);
}

}  // namespace lpt::app
