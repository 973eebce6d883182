#include "plot.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/write_error.hpp"

namespace deformlab::plot {

namespace {

constexpr double kW = 720, kH = 440, kLeft = 80, kRight = 190, kTop = 40, kBottom = 60;
const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                         "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else if (c == '"') o += "&quot;";
    else o += c;
  }
  return o;
}

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// The SVG of `body`, kW wide and `height` high (kH, or more where labels hang below the plot).
void save(const std::filesystem::path& file, const std::string& body, double height = kH) {
  write_file(file.string(), [&](std::ostream& out) {
    out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << height
        << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        << body << "</svg>\n";
  });
}

std::string frame(const std::string& title, const std::string& xlabel, const std::string& ylabel) {
  std::ostringstream s;
  s << "<text x=\"" << kW / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">" << esc(title) << "</text>\n"
    << "<text x=\"" << (kLeft + kW - kRight) / 2 << "\" y=\"" << kH - 15 << "\" text-anchor=\"middle\">" << esc(xlabel)
    << "</text>\n<text transform=\"translate(20," << (kTop + kH - kBottom) / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << esc(ylabel) << "</text>\n"
    << "<rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\"" << kW - kLeft - kRight << "\" height=\""
    << kH - kTop - kBottom << "\" fill=\"none\" stroke=\"black\"/>\n";
  return s.str();
}

}  // namespace

void loglog(const std::filesystem::path& file, const std::string& title, const std::string& xlabel,
            const std::string& ylabel, const std::vector<Series>& series) {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& s : series)
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if (s.x[i] > 0 && s.y[i] > 0) {
        x0 = std::min(x0, s.x[i]); x1 = std::max(x1, s.x[i]);
        y0 = std::min(y0, s.y[i]); y1 = std::max(y1, s.y[i]);
      }
  std::ostringstream b;
  b << frame(title, xlabel, ylabel);
  if (!(x0 <= x1)) {
    b << "<text x=\"" << kW / 2 << "\" y=\"" << kH / 2 << "\" text-anchor=\"middle\">no data</text>\n";
    save(file, b.str());
    return;
  }
  const double lx0 = std::floor(std::log10(x0)), lx1 = std::max(lx0 + 1, std::ceil(std::log10(x1)));
  const double ly0 = std::floor(std::log10(y0)), ly1 = std::max(ly0 + 1, std::ceil(std::log10(y1)));
  auto px = [&](double x) { return kLeft + (std::log10(x) - lx0) / (lx1 - lx0) * (kW - kLeft - kRight); };
  auto py = [&](double y) { return kH - kBottom - (std::log10(y) - ly0) / (ly1 - ly0) * (kH - kTop - kBottom); };
  for (double e = lx0; e <= lx1; ++e)
    b << "<line x1=\"" << px(std::pow(10, e)) << "\" x2=\"" << px(std::pow(10, e)) << "\" y1=\"" << kTop << "\" y2=\""
      << kH - kBottom << "\" stroke=\"#ddd\"/><text x=\"" << px(std::pow(10, e)) << "\" y=\"" << kH - kBottom + 16
      << "\" text-anchor=\"middle\">1e" << e << "</text>\n";
  for (double e = ly0; e <= ly1; ++e)
    b << "<line x1=\"" << kLeft << "\" x2=\"" << kW - kRight << "\" y1=\"" << py(std::pow(10, e)) << "\" y2=\""
      << py(std::pow(10, e)) << "\" stroke=\"#ddd\"/><text x=\"" << kLeft - 6 << "\" y=\"" << py(std::pow(10, e)) + 4
      << "\" text-anchor=\"end\">1e" << e << "</text>\n";
  for (std::size_t k = 0; k < series.size(); ++k) {
    const auto& s = series[k];
    const char* color = kColors[k % std::size(kColors)];
    std::string path;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!(s.x[i] > 0 && s.y[i] > 0)) continue;
      path += (path.empty() ? "M" : " L") + num(px(s.x[i])) + "," + num(py(s.y[i]));
      b << "<circle cx=\"" << px(s.x[i]) << "\" cy=\"" << py(s.y[i]) << "\" r=\"3\" fill=\"" << color << "\"/>\n";
    }
    if (!path.empty())
      b << "<path d=\"" << path << "\" fill=\"none\" stroke=\"" << color << "\" stroke-width=\"2\""
        << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
    const double ly = kTop + 14 + 18 * double(k);
    b << "<line x1=\"" << kW - kRight + 12 << "\" x2=\"" << kW - kRight + 36 << "\" y1=\"" << ly - 4 << "\" y2=\""
      << ly - 4 << "\" stroke=\"" << color << "\" stroke-width=\"2\"" << (s.dashed ? " stroke-dasharray=\"6,4\"" : "")
      << "/><text x=\"" << kW - kRight + 42 << "\" y=\"" << ly << "\">" << esc(s.label) << "</text>\n";
  }
  save(file, b.str());
}

double tick_step(double top) {
  const double quarter = top / 4, decade = std::pow(10.0, std::floor(std::log10(quarter)));
  double step = decade;
  for (double m : {2.0, 2.5, 5.0})
    if (m * decade <= quarter) step = m * decade;
  return step;
}

void stacked_bars(const std::filesystem::path& file, const std::string& title, const std::string& ylabel,
                  const std::vector<std::string>& part_names, const std::vector<Stack>& bars) {
  double top = 0;
  for (const auto& s : bars) {
    double sum = 0;
    for (double v : s.parts) sum += std::max(0.0, v);
    top = std::max(top, sum);
  }
  std::ostringstream b;
  b << frame(title, "", ylabel);
  if (bars.empty() || top <= 0) {
    b << "<text x=\"" << kW / 2 << "\" y=\"" << kH / 2 << "\" text-anchor=\"middle\">no data</text>\n";
    save(file, b.str());
    return;
  }
  const double plot_w = kW - kLeft - kRight, plot_h = kH - kTop - kBottom;
  const double slot = plot_w / double(bars.size()), bw = slot * 0.6;
  // Category labels under their bars, or, where they would overlap, turned to run downwards
  // (the picture grows to hold them).
  std::size_t longest = 0;
  for (const auto& s : bars) longest = std::max(longest, s.category.size());
  const bool turned = double(longest) * 7 > slot;
  const double height = turned ? kH - kBottom + 12 + double(longest) * 6.5 : kH;
  const double step = tick_step(top);
  const int ticks = int(std::ceil(top / step * (1 - 1e-12)));
  top = ticks * step;
  auto py = [&](double v) { return kH - kBottom - v / top * plot_h; };
  for (int t = 0; t <= ticks; ++t) {
    const double v = step * t;
    b << "<line x1=\"" << kLeft << "\" x2=\"" << kW - kRight << "\" y1=\"" << py(v) << "\" y2=\"" << py(v)
      << "\" stroke=\"#ddd\"/><text x=\"" << kLeft - 6 << "\" y=\"" << py(v) + 4 << "\" text-anchor=\"end\">"
      << num(std::round(v * 1000) / 1000) << "</text>\n";
  }
  for (std::size_t i = 0; i < bars.size(); ++i) {
    double base = 0;
    const double x = kLeft + slot * double(i) + (slot - bw) / 2;
    for (std::size_t k = 0; k < bars[i].parts.size(); ++k) {
      const double v = std::max(0.0, bars[i].parts[k]);
      b << "<rect x=\"" << x << "\" y=\"" << py(base + v) << "\" width=\"" << bw << "\" height=\""
        << py(base) - py(base + v) << "\" fill=\"" << kColors[k % std::size(kColors)] << "\"/>\n";
      base += v;
    }
    if (turned)
      b << "<text transform=\"translate(" << x + bw / 2 + 4 << "," << kH - kBottom + 8
        << ") rotate(-90)\" text-anchor=\"end\" font-size=\"11\">" << esc(bars[i].category) << "</text>\n";
    else
      b << "<text x=\"" << x + bw / 2 << "\" y=\"" << kH - kBottom + 16 << "\" text-anchor=\"middle\">"
        << esc(bars[i].category) << "</text>\n";
  }
  for (std::size_t k = 0; k < part_names.size(); ++k) {
    const double ly = kTop + 14 + 18 * double(k);
    b << "<rect x=\"" << kW - kRight + 12 << "\" y=\"" << ly - 10 << "\" width=\"12\" height=\"12\" fill=\""
      << kColors[k % std::size(kColors)] << "\"/><text x=\"" << kW - kRight + 30 << "\" y=\"" << ly << "\">"
      << esc(part_names[k]) << "</text>\n";
  }
  save(file, b.str(), height);
}

}  // namespace deformlab::plot
