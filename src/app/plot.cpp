// `validate --plot` and `identify --plot`: the comparison and the engineering curves drawn as
// SVG, with no plotting library. Every panel is a
// <g class="panel"> whose data-* attributes give its data ranges and its place on the page, so
// that a reader (and the tests) can map the drawn points back to values.
//
// Why not a library: Debian's PLplot 5.15 has an SVG device, but loads it at run time from the
// directory fixed at its build and reads fonts from libplplot-data; when either is missing it
// ends the process from inside the library (status 1), once after writing part of the file. The
// plot must be written whole or not at all, its errors must be momentid's, and its panels must
// carry their data ranges. Plots to adjust (the statistics, the engineering curves) are drawn
// with matplotlib by the Python module as well (python/momentid/plots.py; docs/cli/validate.md,
// "Plot").

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/validate/fit.hpp"
#include "common/json.hpp"
#include "momentid/error.hpp"
#include "momentid/identify.hpp"
#include "momentid/validate.hpp"
#include "momentid/writer.hpp"

namespace momentid {
namespace {

constexpr double kWidth = 960, kLeft = 80, kRight = 24, kPlotWidth = kWidth - kLeft - kRight;
constexpr std::size_t kMaxPoints = 4000;  // a longer window is drawn as per-pixel min and max
constexpr std::size_t kDefaultWindow = 2000;

std::string fixed(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", x);
  return text;
}

std::string label(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '&') {
      out += "&amp;";
    } else if (c == '"') {
      out += "&quot;";
    } else {
      out += c;
    }
  }
  return out;
}

// Tick positions at 1, 2 or 5 times a power of ten, about five across [low, high].
std::vector<double> ticks(double low, double high) {
  const double span = high - low;
  const double raw = span / 5;
  const double power = std::pow(10, std::floor(std::log10(raw)));
  double step = power;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw) {
      step = m * power;
      break;
    }
  }
  std::vector<double> out;
  for (double t = std::ceil(low / step) * step; t <= high + 1e-9 * span; t += step) {
    out.push_back(std::abs(t) < 1e-12 * span ? 0.0 : t);
  }
  return out;
}

class Page {
 public:
  // A framed panel of the given height below the previous one, with its title and axis labels.
  struct Panel {
    double top, height, x0, x1, y0, y1;
    double x(double v) const { return kLeft + (v - x0) / (x1 - x0) * kPlotWidth; }
    double y(double v) const { return top + height - (v - y0) / (y1 - y0) * height; }
  };

  Panel panel(const std::string& cls, const std::string& title, const std::string& xlabel,
              double height, double x0, double x1, double y0, double y1) {
    if (!(x1 > x0)) x1 = x0 + 1;
    if (!(y1 > y0)) {
      const double pad = y0 == 0 ? 1 : std::abs(y0) * 0.1;
      y0 -= pad;
      y1 += pad;
    }
    Panel p{height_ + 28, height, x0, x1, y0, y1};
    close_group();
    body_ << "<g class=\"panel " << cls << "\" data-left=\"" << kLeft << "\" data-top=\""
          << fixed(p.top) << "\" data-width=\"" << kPlotWidth << "\" data-height=\"" << height
          << "\" data-xmin=\"" << json_number(x0) << "\" data-xmax=\"" << json_number(x1)
          << "\" data-ymin=\"" << json_number(y0) << "\" data-ymax=\"" << json_number(y1)
          << "\">\n";
    open_ = true;
    text(kLeft, p.top - 8, title, "start", 14, "bold");
    body_ << "<rect x=\"" << kLeft << "\" y=\"" << fixed(p.top) << "\" width=\"" << kPlotWidth
          << "\" height=\"" << height << "\" fill=\"none\" stroke=\"#444\"/>\n";
    for (double t : ticks(x0, x1)) {
      line(p.x(t), p.top + height, p.x(t), p.top + height + 4, "#444", 1);
      text(p.x(t), p.top + height + 16, label(t), "middle", 11);
    }
    for (double t : ticks(y0, y1)) {
      line(kLeft - 4, p.y(t), kLeft, p.y(t), "#444", 1);
      line(kLeft, p.y(t), kLeft + kPlotWidth, p.y(t), "#e4e4e4", 1);
      text(kLeft - 6, p.y(t) + 4, label(t), "end", 11);
    }
    text(kLeft + kPlotWidth / 2, p.top + height + 32, xlabel, "middle", 12);
    height_ = p.top + height + 40;
    return p;
  }

  void line(double x1, double y1, double x2, double y2, const std::string& stroke, double width,
            const std::string& cls = "") {
    body_ << "<line" << (cls.empty() ? "" : " class=\"" + cls + "\"") << " x1=\"" << fixed(x1)
          << "\" y1=\"" << fixed(y1) << "\" x2=\"" << fixed(x2) << "\" y2=\"" << fixed(y2)
          << "\" stroke=\"" << stroke << "\" stroke-width=\"" << width << "\"/>\n";
  }
  void dashed(double x1, double y1, double x2, double y2, const std::string& stroke,
              const std::string& cls) {
    body_ << "<line class=\"" << cls << "\" x1=\"" << fixed(x1) << "\" y1=\"" << fixed(y1)
          << "\" x2=\"" << fixed(x2) << "\" y2=\"" << fixed(y2) << "\" stroke=\"" << stroke
          << "\" stroke-dasharray=\"6 4\"/>\n";
  }
  void text(double x, double y, const std::string& s, const char* anchor, int size,
            const char* weight = "normal") {
    body_ << "<text x=\"" << fixed(x) << "\" y=\"" << fixed(y) << "\" text-anchor=\"" << anchor
          << "\" font-size=\"" << size << "\" font-weight=\"" << weight << "\">" << escape(s)
          << "</text>\n";
  }
  void polyline(const Panel& p, const std::vector<double>& xs, const std::vector<double>& ys,
                const std::string& cls, const std::string& stroke) {
    body_ << "<polyline class=\"" << cls << "\" fill=\"none\" stroke=\"" << stroke
          << "\" stroke-width=\"1.2\" points=\"";
    for (std::size_t k = 0; k < xs.size(); ++k) {
      body_ << (k ? " " : "") << fixed(p.x(xs[k])) << "," << fixed(p.y(ys[k]));
    }
    body_ << "\"/>\n";
  }
  void shade(const Panel& p, double from, double to, const std::string& cls) {
    const double a = p.x(std::max(from, p.x0)), b = p.x(std::min(to, p.x1));
    if (!(b > a)) return;
    body_ << "<rect class=\"" << cls << "\" x=\"" << fixed(a) << "\" y=\"" << fixed(p.top)
          << "\" width=\"" << fixed(b - a) << "\" height=\"" << p.height
          << "\" fill=\"#000\" fill-opacity=\"0.08\"/>\n";
  }
  // The area between `low` and `high` over `xs`.
  void band(const Panel& p, const std::vector<double>& xs, const std::vector<double>& low,
            const std::vector<double>& high, const std::string& cls) {
    body_ << "<polygon class=\"" << cls << "\" fill=\"#1f77b4\" fill-opacity=\"0.3\" points=\"";
    for (std::size_t k = 0; k < xs.size(); ++k) {
      body_ << (k ? " " : "") << fixed(p.x(xs[k])) << "," << fixed(p.y(low[k]));
    }
    for (std::size_t k = xs.size(); k-- > 0;) {
      body_ << " " << fixed(p.x(xs[k])) << "," << fixed(p.y(high[k]));
    }
    body_ << "\"/>\n";
  }
  void marker(const Panel& p, double x, double y, const std::string& cls, const std::string& fill) {
    body_ << "<circle class=\"" << cls << "\" cx=\"" << fixed(p.x(x)) << "\" cy=\"" << fixed(p.y(y))
          << "\" r=\"4\" fill=\"" << fill << "\"/>\n";
  }
  void legend(const Panel& p, const std::vector<std::pair<std::string, std::string>>& entries) {
    double x = kLeft + kPlotWidth - 10;
    for (auto it = entries.rbegin(); it != entries.rend(); ++it) {
      text(x, p.top - 8, it->first, "end", 12);
      x -= 7.0 * static_cast<double>(it->first.size()) + 6;
      line(x - 22, p.top - 12, x - 2, p.top - 12, it->second, 2);
      x -= 34;
    }
  }

  std::string svg() {
    close_group();
    std::ostringstream out;
    out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\""
        << fixed(height_ + 10) << "\" viewBox=\"0 0 " << kWidth << " " << fixed(height_ + 10)
        << "\" font-family=\"sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        << body_.str() << "</svg>\n";
    return out.str();
  }

  void heading(const std::string& s) {
    close_group();
    text(kLeft, height_ + 22, s, "start", 15, "bold");
    height_ += 30;
  }

 private:
  void close_group() {
    if (open_) body_ << "</g>\n";
    open_ = false;
  }

  std::ostringstream body_;
  double height_ = 0;
  bool open_ = false;
};

// At most kMaxPoints points: per bucket of rows, the minimum and the maximum in their order.
void thin(std::vector<double>& xs, std::vector<std::vector<double>*> series) {
  const std::size_t n = xs.size();
  if (n <= kMaxPoints) return;
  const std::size_t buckets = kMaxPoints / 2;
  std::vector<std::size_t> keep;
  for (std::size_t b = 0; b < buckets; ++b) {
    const std::size_t from = b * n / buckets, to = (b + 1) * n / buckets;
    if (from >= to) continue;
    // The rows of the first series' extremes; the other series follow the same rows.
    const std::vector<double>& s = *series.front();
    const auto [low, high] =
        std::minmax_element(s.begin() + static_cast<long>(from), s.begin() + static_cast<long>(to));
    const auto a = static_cast<std::size_t>(low - s.begin());
    const auto c = static_cast<std::size_t>(high - s.begin());
    keep.push_back(std::min(a, c));
    if (a != c) keep.push_back(std::max(a, c));
  }
  const auto pick = [&](std::vector<double>& v) {
    std::vector<double> out;
    for (std::size_t k : keep) out.push_back(v[k]);
    v = std::move(out);
  };
  pick(xs);
  for (std::vector<double>* s : series) pick(*s);
}

void range_of(const std::vector<double>& v, double& low, double& high) {
  for (double x : v) {
    if (!std::isfinite(x)) continue;
    low = std::min(low, x);
    high = std::max(high, x);
  }
}

void draw_correlation(Page& page, const CorrelationCheck& c, const std::string& output) {
  const int first = c.first_lag;
  const int last = first + static_cast<int>(c.values.size()) - 1;
  double low = -1.3 * c.band, high = 1.3 * c.band;
  range_of(c.values, low, high);
  const std::string title =
      c.with.empty() ? output + ": autocorrelation of the error, 99% band"
                     : output + ": cross-correlation of the error with " + c.with + ", 99% band";
  const Page::Panel p =
      page.panel(c.with.empty() ? "autocorrelation" : "cross-correlation", title,
                 c.with.empty() ? "lag (samples)" : "lag (samples; positive: the input leads)", 150,
                 first - 1, last + 1, std::min(low, 0.0), std::max(high, 0.0));
  page.line(p.x(first - 1), p.y(0), p.x(last + 1), p.y(0), "#444", 1);
  page.dashed(p.x(first - 1), p.y(c.band), p.x(last + 1), p.y(c.band), "#1f77b4", "band");
  page.dashed(p.x(first - 1), p.y(-c.band), p.x(last + 1), p.y(-c.band), "#1f77b4", "band");
  for (std::size_t k = 0; k < c.values.size(); ++k) {
    const double lag = first + static_cast<int>(k);
    const bool outside = std::abs(c.values[k]) > c.band;
    page.line(p.x(lag), p.y(0), p.x(lag), p.y(c.values[k]), outside ? "#d62728" : "#333", 2,
              outside ? "stem outside" : "stem");
  }
}

// One statistic of the statistical validation (StatisticCheck) against its band: the runs'
// smallest to largest shaded, their mean, the record's; a spectral density as its log10, and
// a statistic at one or two points (a prediction error, its biases) as bars and marks.
void draw_statistic(Page& page, const StatisticCheck& c) {
  struct Kind {
    const char* kind;
    const char* xlabel;
    const char* ylabel;
  };
  static constexpr Kind kKinds[] = {
      {"psd", "frequency (Hz)", "log10 power spectral density"},
      {"distribution", "probability", "quantile"},
      {"crossings", "level", "up-crossing rate"},
      {"prediction", "time ahead (s)", "rms prediction error"},
      {"bias", "state predicted (index)", "slope of the prediction error"}};
  const Kind* kind = std::find_if(std::begin(kKinds), std::end(kKinds),
                                  [&](const Kind& k) { return c.kind == k.kind; });
  if (kind == std::end(kKinds) || c.at.empty()) return;
  const bool logarithmic = c.kind == "psd";
  const auto scaled = [&](std::vector<double> v) {
    if (!logarithmic) return v;
    double floor = INFINITY;
    for (const std::vector<double>* all : {&c.measured, &c.mean, &c.low, &c.high}) {
      for (double x : *all) {
        if (x > 0) floor = std::min(floor, x);
      }
    }
    for (double& x : v) x = std::log10(std::max(x, floor));
    return v;
  };
  const std::vector<double> measured = scaled(c.measured), mean = scaled(c.mean),
                            low = scaled(c.low), high = scaled(c.high);
  double y0 = INFINITY, y1 = -INFINITY, x0 = c.at.front(), x1 = c.at.back();
  for (const std::vector<double>* v : {&measured, &mean, &low, &high}) range_of(*v, y0, y1);
  const bool points = c.at.size() <= 2;
  if (points) {
    x0 -= 0.5;
    x1 += 0.5;
  }
  // The verdict is the distance's (StatisticCheck): the record against the runs' mean, over the
  // limit that the runs' own distances set, not whether each point lies in the shaded range.
  char verdict[96];
  std::snprintf(verdict, sizeof verdict, "distance %.3g, limit %.3g: %s", c.distance, c.limit,
                c.inside() ? "inside" : "outside");
  const Page::Panel p =
      page.panel("statistic " + c.kind, c.output + " " + kind->ylabel + ": " + verdict,
                 kind->xlabel, 150, x0, x1, y0, y1);
  const std::string color = c.inside() ? "#333333" : "#d62728";
  if (points) {
    for (std::size_t k = 0; k < c.at.size(); ++k) {
      page.line(p.x(c.at[k]), p.y(low[k]), p.x(c.at[k]), p.y(high[k]), "#9ecae1", 10, "band");
      page.marker(p, c.at[k], mean[k], "mean", "#1f77b4");
      page.marker(p, c.at[k], measured[k], "measured", color);
    }
  } else {
    page.band(p, c.at, low, high, "band");
    page.polyline(p, c.at, mean, "mean", "#1f77b4");
    page.polyline(p, c.at, measured, "measured", color);
  }
  page.legend(p, {{"record", color}, {"runs: mean, smallest to largest", "#1f77b4"}});
}

// A curve with its 95% band (1.96 standard errors) over the points where both are finite.
void draw_curve(Page& page, const std::string& cls, const std::string& title,
                const std::string& xlabel, const std::vector<double>& at,
                const std::vector<double>& value, const std::vector<double>& error) {
  std::vector<double> xs, ys, low, high;
  for (std::size_t k = 0; k < at.size(); ++k) {
    if (!std::isfinite(value[k]) || !std::isfinite(error[k])) continue;
    xs.push_back(at[k]);
    ys.push_back(value[k]);
    low.push_back(value[k] - 1.96 * error[k]);
    high.push_back(value[k] + 1.96 * error[k]);
  }
  if (xs.empty()) return;
  double y0 = INFINITY, y1 = -INFINITY;
  range_of(low, y0, y1);
  range_of(high, y0, y1);
  const Page::Panel p = page.panel(cls, title, xlabel, 220, xs.front(), xs.back(), y0, y1);
  page.band(p, xs, low, high, "band");
  page.polyline(p, xs, ys, "estimate", "#333333");
  page.legend(p, {{"estimate", "#333333"}, {"95% band", "#1f77b4"}});
}

}  // namespace

void write_engineering_plot(const IdentifyResult& result, const std::string& path) {
  const NonlinearCurves curves = nonlinear_curves(result);
  if (curves.displacement.empty()) {
    throw UsageError("plot", "no restoring force or backbone to draw: " + curves.unavailable);
  }
  Page page;
  page.heading("identify " + result.model->name() + " on " + result.data_name);
  draw_curve(page, "restoring-force",
             "restoring force R(" + curves.state + ") = m times minus the acceleration at rest",
             curves.state, curves.displacement, curves.force, curves.force_se);
  draw_curve(page, "backbone", "backbone: frequency of free undamped oscillation (Hz)",
             "amplitude of " + curves.state, curves.amplitude, curves.frequency_hz,
             curves.frequency_se);
  write_whole_file(path, page.svg());
}

void write_plot(const ValidateResult& result, const std::string& path,
                std::optional<std::pair<double, double>> window) {
  const Model& model = *result.model;
  const Record& record = result.replay.record;
  const RecordRun& run = record.runs.front();
  const std::size_t skip = result.skip.front();
  const auto time = [&](std::size_t n) {
    return run.time.empty() ? static_cast<double>(n) * record.dt : run.time[n];
  };
  std::size_t from = skip, to = std::min(run.rows(), skip + kDefaultWindow);
  if (window) {
    from = run.rows();
    to = 0;
    for (std::size_t n = 0; n < run.rows(); ++n) {
      if (time(n) >= window->first && time(n) <= window->second) {
        from = std::min(from, n);
        to = n + 1;
      }
    }
    if (from >= to) {
      throw UsageError("--window: no row of the first run lies in " + label(window->first) + ":" +
                       label(window->second) + " (it spans " + label(time(0)) + " to " +
                       label(time(run.rows() - 1)) + ")");
    }
  }
  Page page;
  std::string title = "validate " + model.name() + " on " + record.name;
  if (record.runs.size() > 1) title += " (run " + std::to_string(run.number) + " shown)";
  page.heading(title);
  for (const OutputFit& fit : result.outputs) {
    const std::vector<double>& y =
        run.columns[static_cast<std::size_t>(record.column_of(output_variable(model, fit.state)))];
    const std::vector<double>& sim = simulated_output(model, result.replay, 0, fit.state);
    std::vector<double> xs, measured, simulated, error;
    for (std::size_t n = from; n < to; ++n) {
      xs.push_back(time(n));
      measured.push_back(y[n]);
      simulated.push_back(sim[n]);
      error.push_back(y[n] - sim[n]);
    }
    std::vector<double> error_xs = xs;
    thin(xs, {&measured, &simulated});
    thin(error_xs, {&error});
    double low = INFINITY, high = -INFINITY;
    range_of(measured, low, high);
    range_of(simulated, low, high);
    char fit_text[64];
    std::snprintf(fit_text, sizeof fit_text, " (fit %.2f%%)", fit.fit);
    const Page::Panel signals =
        page.panel("signals", fit.name + ": measured and simulated" + std::string(fit_text), "t",
                   220, time(from), time(to - 1), low, high);
    page.shade(signals, time(0), time(skip), "skipped");
    page.polyline(signals, xs, measured, "measured", "#333333");
    page.polyline(signals, xs, simulated, "simulated", "#d62728");
    page.legend(signals, {{"measured", "#333333"}, {"simulated", "#d62728"}});
    double e_low = INFINITY, e_high = -INFINITY;
    range_of(error, e_low, e_high);
    const Page::Panel errors =
        page.panel("error", fit.name + ": measured - simulated", "t", 120, time(from), time(to - 1),
                   std::min(e_low, 0.0), std::max(e_high, 0.0));
    page.shade(errors, time(0), time(skip), "skipped");
    page.polyline(errors, error_xs, error, "error", "#1f77b4");
  }
  for (const OutputFit& fit : result.outputs) {
    if (!fit.autocorrelation) continue;
    draw_correlation(page, *fit.autocorrelation, fit.name);
    for (const CorrelationCheck& c : fit.cross) draw_correlation(page, c, fit.name);
  }
  if (result.statistics.compared) {
    page.heading("the response's statistics against " + std::to_string(result.statistics.runs) +
                 " simulations");
    for (const StatisticCheck& c : result.statistics.checks) draw_statistic(page, c);
  }
  write_whole_file(path, page.svg());
}

}  // namespace momentid
