// Progress on the terminal. On a terminal a line redraws itself (carriage return) at most every
// 0.25 s; when stderr is a file or a pipe (logs, CI, a cluster job) it prints a plain line every
// 5 s instead, so a long run's log stays readable line by line.
#include "apps/commands.h"
#include <chrono>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <unistd.h>

namespace lpt::app {

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

bool stderr_is_terminal() { return isatty(fileno(stderr)) != 0; }

/// Seconds between two progress lines, and how each ends.
struct LineStyle {
    double interval;
    const char* begin;
    const char* end;
};

LineStyle line_style() {
    static const LineStyle style = stderr_is_terminal() ? LineStyle{0.25, "\r", "   "} : LineStyle{5.0, "", "\n"};
    return style;
}

/// State shared by one console reporter's callbacks.
struct ConsoleState {
    bool quiet = false;
    double last = -1e30;
    bool line_open = false;  ///< a redrawn progress line waits for its newline
};

void close_line(ConsoleState& s) {
    if (s.line_open) std::fputc('\n', stderr);
    s.line_open = false;
}

bool print_progress(ConsoleState& s, const pipeline::StageProgress& p) {
    const LineStyle style = line_style();
    const double t = now();
    if (s.quiet || (t - s.last < style.interval && p.step < p.total)) return true;
    s.last = t;
    const int done = p.step - p.start, left = p.total - p.step;
    const double rate = done / std::max(1e-9, p.seconds);
    std::fprintf(stderr, "%s[%s] %d/%d | %s | %.1f/s | ETA %.0f s%s", style.begin, p.stage, p.step, p.total,
                 p.status.c_str(), rate, left / std::max(1e-9, rate), style.end);
    std::fflush(stderr);
    s.line_open = style.begin[0] == '\r';
    if (p.step >= p.total) close_line(s);
    return true;
}

void print_note(ConsoleState& s, const std::string& text) {
    const bool warning = text.rfind("warning:", 0) == 0;
    if (s.quiet && !warning) return;
    close_line(s);
    std::fprintf(stderr, "%s%s\n", warning ? "latentpt: " : "", text.c_str());
}

}  // namespace

pipeline::Reporter console_reporter(bool quiet) {
    auto state = std::make_shared<ConsoleState>();
    state->quiet = quiet;
    pipeline::Reporter r;
    r.progress = [state](const pipeline::StageProgress& p) { return print_progress(*state, p); };
    r.note = [state](const std::string& text) { print_note(*state, text); };
    return r;
}

Progress::Progress(std::string label, bool enabled) : m_label(std::move(label)), m_enabled(enabled), m_start(now()) {}

void Progress::update(double fraction, uint64_t rays) {
    if (!m_enabled) return;
    const LineStyle style = line_style();
    double t = now();
    if (t - m_last < style.interval && fraction < 1.0) return;
    m_last = t;
    double el = t - m_start;
    double eta = fraction > 0 ? el * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr, "%s[%s] %5.1f%% | %6.2f Mrays/s | elapsed %.1f s | ETA %.1f s%s", style.begin, m_label.c_str(),
                 100.0 * fraction, el > 0 ? rays / el * 1e-6 : 0.0, el, eta, style.end);
    std::fflush(stderr);
}

void Progress::finish(uint64_t rays) {
    if (!m_enabled) return;
    double el = now() - m_start;
    std::fprintf(stderr, "%s[%s] done in %.2f s | %.2f Mrays/s%s\n", line_style().begin, m_label.c_str(), el,
                 el > 0 ? rays / el * 1e-6 : 0.0, stderr_is_terminal() ? "                              " : "");
}

}  // namespace lpt::app
