// Pictures of signals over time as SVG, the way a scope shows an axis: one panel per signal group, stacked
// over a shared time axis, each with a grid, tick labels, the quantity and unit on its y axis and a
// legend. Plain SVG 1.1 text, written without a library; rsvg-convert turns it into PNG.
#pragma once

#include <string>
#include <vector>

namespace vecat::telemetry {

struct Series {
    std::string label;
    std::vector<double> t;  // s
    std::vector<double> y;
    bool step = false;    // draw as a staircase (states, words)
    bool dashed = false;  // demand values, drawn over the actual ones
};

struct Panel {
    std::string quantity;  // "position"
    std::string unit;      // "inc" ("" for none)
    std::vector<Series> series;
};

struct Plot {
    std::string title;
    std::string time_label = "time [s]";
    std::vector<Panel> panels;
    int width = 1100;        // px
    int panel_height = 230;  // px
};

// Tick positions 1-2-5 x 10^k covering [lo, hi], about `target` of them.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

std::string render_svg(const Plot& p);

// Converts an SVG file to PNG with rsvg-convert (Debian librsvg2-bin). False with a reason.
bool svg_to_png(const std::string& svg_path, const std::string& png_path, std::string* why = nullptr);

}  // namespace vecat::telemetry
