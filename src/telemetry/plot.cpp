#include "telemetry/plot.hpp"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

extern char** environ;

namespace vecat::telemetry {
namespace {

// Colours a reader tells apart (the "tab10" palette), in the order series appear.
constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

std::string escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        switch (c) {
            case '&':
                o += "&amp;";
                break;
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '"':
                o += "&quot;";
                break;
            default:
                o += c;
        }
    }
    return o;
}

// Tick label: as few digits as the tick step needs.
std::string tick_label(double v, double step) {
    if (std::abs(v) < step * 1e-9) v = 0;
    const int decimals = step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9));
    return fmt::format("{:.{}f}", v, std::clamp(decimals, 0, 9));
}

struct Range {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -std::numeric_limits<double>::infinity();
    void add(double v) {
        if (!std::isfinite(v)) return;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    bool empty() const { return lo > hi; }
};

// At most about two points per pixel column: the minimum and maximum of each column, in time order, so
// that peaks survive the reduction.
std::vector<std::pair<double, double>> reduce(const Series& s, double t0, double t1, int columns) {
    std::vector<std::pair<double, double>> out;
    const std::size_t n = std::min(s.t.size(), s.y.size());
    if (n <= static_cast<std::size_t>(4 * columns) || t1 <= t0) {
        for (std::size_t i = 0; i < n; ++i)
            if (std::isfinite(s.y[i])) out.emplace_back(s.t[i], s.y[i]);
        return out;
    }
    std::size_t i = 0;
    while (i < n) {
        const int col = static_cast<int>((s.t[i] - t0) / (t1 - t0) * columns);
        std::size_t lo = i, hi = i, j = i;
        for (; j < n && static_cast<int>((s.t[j] - t0) / (t1 - t0) * columns) == col; ++j) {
            if (s.y[j] < s.y[lo]) lo = j;
            if (s.y[j] > s.y[hi]) hi = j;
        }
        const std::size_t a = std::min(lo, hi), b = std::max(lo, hi);
        out.emplace_back(s.t[a], s.y[a]);
        if (b != a) out.emplace_back(s.t[b], s.y[b]);
        i = j;
    }
    return out;
}

// 10^-3 -> "⁻³" for the axis label.
std::string superscript(int e) {
    static const char* kDigits[] = {"\u2070", "\u00b9", "\u00b2", "\u00b3", "\u2074",
                                    "\u2075", "\u2076", "\u2077", "\u2078", "\u2079"};
    std::string s = e < 0 ? "\u207b" : "";
    for (char c : std::to_string(e < 0 ? -e : e))
        s += kDigits[c - '0'];
    return s;
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
    std::vector<double> ticks;
    if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return ticks;
    const double raw = (hi - lo) / std::max(target, 2);
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (m * mag >= raw) {
            step = m * mag;
            break;
        }
    // Multiples of the step, each computed anew so that errors do not add up.
    for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + step * 1e-9; k += 1)
        ticks.push_back(k == 0 ? 0.0 : k * step);
    return ticks;
}

std::string render_svg(const Plot& p) {
    constexpr int kLeft = 96, kTop = 48, kGap = 26, kBottom = 58;
    // The legend column is as wide as the longest label (about 7 px per character at this font size);
    // the picture grows by what the default 210 px do not hold, so the plotting area keeps its width.
    std::size_t longest = 0;
    for (const auto& pan : p.panels)
        for (const auto& s : pan.series)
            longest = std::max(longest, s.label.size());
    const int kRight = std::max(210, 54 + 7 * static_cast<int>(longest));
    const int n = static_cast<int>(p.panels.size());
    const int w = p.width + (kRight - 210), ph = p.panel_height;
    const int pw = w - kLeft - kRight;
    const int h = kTop + n * ph + std::max(0, n - 1) * kGap + kBottom;

    Range tr;
    for (const auto& pan : p.panels)
        for (const auto& s : pan.series)
            for (double t : s.t)
                tr.add(t);
    if (tr.empty()) tr = {0, 1};
    if (tr.lo > 0 && tr.lo < 0.05 * (tr.hi - tr.lo)) tr.lo = 0;  // start at time zero
    if (tr.hi - tr.lo < 1e-9) tr.hi = tr.lo + 1;
    const auto tticks = nice_ticks(tr.lo, tr.hi, 10);
    const double tstep = tticks.size() > 1 ? tticks[1] - tticks[0] : 1;

    std::string o;
    o += fmt::format(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
        "font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"13\">\n"
        "<rect width=\"{0}\" height=\"{1}\" fill=\"white\"/>\n",
        w, h);
    o += fmt::format("<text x=\"{}\" y=\"28\" font-size=\"17\" font-weight=\"bold\">{}</text>\n", kLeft,
                     escape(p.title));

    for (int k = 0; k < n; ++k) {
        const Panel& pan = p.panels[static_cast<std::size_t>(k)];
        const int y0 = kTop + k * (ph + kGap);
        Range yr;
        for (const auto& s : pan.series)
            for (double v : s.y)
                yr.add(v);
        if (yr.empty()) yr = {0, 1};
        if (yr.hi - yr.lo < 1e-12) {
            const double pad = std::max(1.0, std::abs(yr.hi) * 0.05);
            yr.lo -= pad;
            yr.hi += pad;
        } else {
            const double pad = (yr.hi - yr.lo) * 0.06;
            yr.lo -= pad;
            yr.hi += pad;
        }
        // Large or small values: a common power of ten (a multiple of 3) goes into the axis label.
        const double amax = std::max(std::abs(yr.lo), std::abs(yr.hi));
        int exp3 = 0;
        if (amax >= 1e5 || amax < 1e-2) exp3 = static_cast<int>(std::floor(std::log10(amax) / 3.0)) * 3;
        const double scale = std::pow(10.0, -exp3);
        const auto yticks = nice_ticks(yr.lo * scale, yr.hi * scale, 5);
        const double ystep = yticks.size() > 1 ? yticks[1] - yticks[0] : 1;
        auto X = [&](double t) { return kLeft + (t - tr.lo) / (tr.hi - tr.lo) * pw; };
        auto Y = [&](double v) { return y0 + ph - (v - yr.lo) / (yr.hi - yr.lo) * ph; };

        o += fmt::format(
            "<g>\n<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#fbfbfb\" "
            "stroke=\"#333\" stroke-width=\"1\"/>\n",
            kLeft, y0, pw, ph);
        for (double t : tticks)
            o += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#ddd\"/>\n",
                             X(t), y0, y0 + ph);
        for (double v : yticks) {
            const double y = Y(v / scale);
            o += fmt::format("<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#ddd\"/>\n",
                             kLeft, y, kLeft + pw);
            o += fmt::format("<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#333\"/>\n",
                             kLeft - 5, y, kLeft);
            o += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", kLeft - 8,
                             y + 4.5, tick_label(v, ystep));
        }
        if (yr.lo < 0 && yr.hi > 0)
            o += fmt::format("<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#999\"/>\n",
                             kLeft, Y(0), kLeft + pw);
        // Quantity and unit on the y axis, rotated.
        std::string unit = pan.unit;
        if (exp3 != 0) unit = fmt::format("\u00d710{}{}{}", superscript(exp3), unit.empty() ? "" : " ", unit);
        const std::string ylabel = unit.empty() ? pan.quantity : pan.quantity + " [" + unit + "]";
        o += fmt::format(
            "<text transform=\"translate({},{}) rotate(-90)\" text-anchor=\"middle\" "
            "font-size=\"14\">{}</text>\n",
            22, y0 + ph / 2, escape(ylabel));
        // Curves, clipped to the panel.
        o += fmt::format(
            "<clipPath id=\"c{0}\"><rect x=\"{1}\" y=\"{2}\" width=\"{3}\" height=\"{4}\"/></clipPath>\n", k,
            kLeft, y0, pw, ph);
        for (std::size_t si = 0; si < pan.series.size(); ++si) {
            const Series& s = pan.series[si];
            const char* colour = kColours[si % std::size(kColours)];
            const auto pts = reduce(s, tr.lo, tr.hi, pw);
            if (pts.empty()) continue;
            std::string d;
            d.reserve(pts.size() * 16);
            double prev_y = 0;
            for (std::size_t i = 0; i < pts.size(); ++i) {
                const double x = X(pts[i].first), y = Y(pts[i].second);
                if (i == 0)
                    d += fmt::format("{:.1f},{:.1f}", x, y);
                else if (s.step)
                    d += fmt::format(" {:.1f},{:.1f} {:.1f},{:.1f}", x, prev_y, x, y);
                else
                    d += fmt::format(" {:.1f},{:.1f}", x, y);
                prev_y = y;
            }
            o += fmt::format(
                "<polyline clip-path=\"url(#c{})\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.6\" "
                "stroke-linejoin=\"round\"{} points=\"{}\"/>\n",
                k, colour, s.dashed ? " stroke-dasharray=\"6,4\"" : "", d);
            // Legend entry to the right of the panel.
            const int ly = y0 + 14 + static_cast<int>(si) * 20;
            o += fmt::format(
                "<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"{3}\" stroke-width=\"3\"{4}/>\n",
                kLeft + pw + 12, ly, kLeft + pw + 36, colour, s.dashed ? " stroke-dasharray=\"5,3\"" : "");
            o += fmt::format("<text x=\"{}\" y=\"{}\">{}</text>\n", kLeft + pw + 42, ly + 4.5,
                             escape(s.label));
        }
        // Time ticks on every panel, their labels under the last one.
        for (double t : tticks) {
            o += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#333\"/>\n",
                             X(t), y0 + ph, y0 + ph + 5);
            if (k == n - 1)
                o += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", X(t),
                                 y0 + ph + 20, tick_label(t, tstep));
        }
        o += "</g>\n";
    }
    o += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"14\">{}</text>\n",
                     kLeft + pw / 2, h - 14, escape(p.time_label));
    o += "</svg>\n";
    return o;
}

bool svg_to_png(const std::string& svg_path, const std::string& png_path, std::string* why) {
    std::vector<std::string> args{"rsvg-convert", "-b", "white", "-o", png_path, svg_path};
    std::vector<char*> argv;
    for (auto& a : args)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    if (const int rc = posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ); rc != 0) {
        if (why)
            *why = std::string("cannot run rsvg-convert (Debian package librsvg2-bin): ") + std::strerror(rc);
        return false;
    }
    int st = 0;
    if (waitpid(pid, &st, 0) < 0 || !WIFEXITED(st) || WEXITSTATUS(st) != 0) {
        if (why) *why = "rsvg-convert failed on " + svg_path;
        return false;
    }
    return true;
}

}  // namespace vecat::telemetry
