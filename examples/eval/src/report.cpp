// The definitions of what driftcorr/eval/report.h declares.
#include "driftcorr/eval/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "driftcorr/mapping/atomic_file.h"

namespace driftcorr::eval {
namespace {

// ---- formatting helpers ---------------------------------------------------------------------

std::string Fmt(const char* format, double v) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), format, v);
    return buf;
}

std::string Fmt(const char* format, const char* text) {
    char buf[256];
    std::snprintf(buf, sizeof(buf), format, text);
    return buf;
}

std::string Num(double v, int decimals = 2) {
    if (!std::isfinite(v)) return "-";
    char f[16];
    std::snprintf(f, sizeof(f), "%%.%df", decimals);
    return Fmt(f, v);
}

std::string JsonNum(double v) { return std::isfinite(v) ? Fmt("%.6g", v) : "null"; }

std::string JsonString(const std::string& s) {
    std::string out = "\"";
    for (const char ch : s) {
        const unsigned char c = static_cast<unsigned char>(ch);
        if (c == '"')
            out += "\\\"";
        else if (c == '\\')
            out += "\\\\";
        else if (c == '\n')
            out += "\\n";
        else if (c == '\t')
            out += "\\t";
        else if (c < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(c));
            out += buf;
        } else
            out += ch;
    }
    return out + "\"";
}

std::string XmlEscape(const std::string& s) {
    std::string out;
    for (const char c : s) {
        if (c == '&')
            out += "&amp;";
        else if (c == '<')
            out += "&lt;";
        else if (c == '>')
            out += "&gt;";
        else if (c == '"')
            out += "&quot;";
        else
            out += c;
    }
    return out;
}

// Markdown table cells must not contain a bare '|' or a newline.
std::string MdCell(const std::string& s) {
    std::string out;
    for (const char c : s) {
        if (c == '|')
            out += "\\|";
        else if (c == '\n')
            out += ' ';
        else
            out += c;
    }
    return out;
}

// The methods in column order: those of the first evaluated scenario, else the defaults.
std::vector<Method> Columns(const std::vector<ScenarioEvaluation>& evals) {
    for (const ScenarioEvaluation& ev : evals) {
        if (ev.ok() && !ev.methods.empty()) {
            std::vector<Method> m;
            for (const MethodResult& r : ev.methods) m.push_back(r.method);
            return m;
        }
    }
    return DefaultMethods();
}

const char* MethodColour(Method m) {
    switch (m) {
        case Method::kEstimate:
            return "#d62728";  // red
        case Method::kPaper:
            return "#ff7f0e";  // orange
        case Method::kDriftcorr:
            return "#1f77b4";  // blue
        case Method::kOnline:
            return "#2ca02c";  // green
    }
    return "#9467bd";
}

std::string PlotName(const ScenarioEvaluation& ev, const char* kind) {
    return ev.label + "_" + kind + ".svg";
}

// A round step (1, 2 or 5 times a power of ten) giving about `count` intervals over `range`.
double NiceStep(double range, int count) {
    if (!(range > 0.0)) return 1.0;
    const double raw = range / count;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    for (const double f : {1.0, 2.0, 5.0, 10.0}) {
        if (f * mag >= raw) return f * mag;
    }
    return 10.0 * mag;
}

// SVG polyline points, dropping points closer than min_px to the last kept one.
template <typename ToPx>
std::string PolylinePoints(const std::vector<Eigen::Vector2d>& pts, const ToPx& to_px,
                           double min_px = 0.7) {
    std::string out;
    Eigen::Vector2d last(1e18, 1e18);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const Eigen::Vector2d q = to_px(pts[i]);
        if (i + 1 < pts.size() && (q - last).norm() < min_px) continue;
        char buf[48];
        std::snprintf(buf, sizeof(buf), "%.1f,%.1f ", q.x(), q.y());
        out += buf;
        last = q;
    }
    if (!out.empty()) out.pop_back();
    return out;
}

// ---- the console table ----------------------------------------------------------------------

std::string ConsoleCell(const MethodResult* r, bool has_gt, bool timed) {
    std::string s;
    if (r == nullptr || !r->ok) {
        s = Fmt("%-17s", "failed");
    } else if (r->metrics) {
        s = Fmt("%8.2f", r->metrics->ate_m) + Fmt(" %8.2f", r->metrics->final_m);
    } else {
        s = Fmt("map %4.2f", r->mean_map_distance_m.value_or(NAN)) +
            Fmt("%9s", has_gt ? "" : "(no GT)");
    }
    if (timed) {
        s +=
            r && r->ok ? Fmt(" %8.2f", r->wall_s) + Fmt(" %8.0f", r->poses_per_s) : Fmt("%18s", "");
    }
    return s;
}

}  // namespace

std::string FormatTable(const std::vector<ScenarioEvaluation>& evals) {
    const std::vector<Method> cols = Columns(evals);
    std::ostringstream out;
    std::string h1 = Fmt("%-30s", "scenario") + Fmt("%6s", "poses");
    std::string h2 = Fmt("%-30s", "") + Fmt("%6s", "");
    for (const Method m : cols) {
        const bool timed = m != Method::kEstimate;
        const int width = timed ? 35 : 17;
        char buf[64];
        std::snprintf(buf, sizeof(buf), " | %-*s", width, ToString(m).c_str());
        h1 += buf;
        h2 += std::string(" | ") + Fmt("%8s", "ATE [m]") + Fmt(" %8s", "final") +
              (timed ? Fmt(" %8s", "time [s]") + Fmt(" %8s", "poses/s") : "");
    }
    out << h1 << "\n" << h2 << "\n" << std::string(h2.size(), '-') << "\n";
    std::vector<std::string> notes;
    for (const ScenarioEvaluation& ev : evals) {
        out << Fmt("%-30s", ev.label.substr(0, 30).c_str());
        if (!ev.ok()) {
            out << Fmt("%6s", "-") << " | FAILED: " << ev.error << "\n";
            continue;
        }
        out << Fmt("%6.0f", double(ev.poses));
        for (const Method m : cols) {
            const MethodResult* r = ev.Find(m);
            out << " | " << ConsoleCell(r, ev.has_ground_truth, m != Method::kEstimate);
            if (r && !r->ok)
                notes.push_back(ev.label + ": " + ToString(m) + " failed: " + r->message);
        }
        if (!ev.has_ground_truth)
            notes.push_back(ev.label + ": no ground truth; mean map distance [m] shown");
        out << "\n";
    }
    for (const ScenarioEvaluation& ev : evals) {
        const MethodResult* d = ev.Find(Method::kDriftcorr);
        if (!d || !d->verdict) continue;
        out << "  verdict " << ev.label << ": " << ToString(d->verdict->level);
        if (d->covariance_in_95) {
            out << " (true error inside the 95 % region: " << Num(100.0 * *d->covariance_in_95, 1)
                << " % of poses)";
        }
        out << "\n";
        for (const std::string& reason : d->verdict->reasons) out << "    " << reason << "\n";
    }
    for (const std::string& n : notes) out << "  note: " << n << "\n";
    if (const double ratio = SpeedRatioPaperOverDriftcorr(evals); ratio > 0.0) {
        out << "speed: paper / driftcorr solver time = " << Num(ratio, 2) << " (summed over "
            << "scenarios where both ran)\n";
    }
    return out.str();
}

double SpeedRatioPaperOverDriftcorr(const std::vector<ScenarioEvaluation>& evals) {
    double paper = 0.0, ours = 0.0;
    for (const ScenarioEvaluation& ev : evals) {
        const MethodResult* p = ev.Find(Method::kPaper);
        const MethodResult* d = ev.Find(Method::kDriftcorr);
        if (ev.ok() && p && d && p->ok && d->ok) {
            paper += p->wall_s;
            ours += d->wall_s;
        }
    }
    return ours > 0.0 ? paper / ours : 0.0;
}

// ---- summary.md -----------------------------------------------------------------------------

namespace {

std::vector<std::string> MdMethodHeaders(Method m) {
    const std::string n = ToString(m);
    std::vector<std::string> h = {n + " ATE [m]", "final [m]",       "max [m]", "p90 [m]",
                                  "drift [%]",    "right floor [%]", "map [m]"};
    if (m != Method::kEstimate) {
        h.push_back("time [s]");
        h.push_back("poses/s");
        h.push_back("verdict");
    }
    if (m == Method::kDriftcorr) h.push_back("in 95 % [%]");
    return h;
}

std::vector<std::string> MdMethodCells(const ScenarioEvaluation& ev, Method m) {
    std::vector<std::string> c;
    const MethodResult* r = ev.Find(m);
    const std::size_t n = MdMethodHeaders(m).size();
    if (r == nullptr || !r->ok) {
        c.push_back(r ? "**failed**" : "-");
        c.resize(n, "");
        return c;
    }
    if (r->metrics) {
        for (const double v : {r->metrics->ate_m, r->metrics->final_m, r->metrics->max_m,
                               r->metrics->p90_m, r->metrics->drift_pct}) {
            c.push_back(Num(v));
        }
        c.push_back(ev.mode == "indoor3d" ? Num(100.0 * r->metrics->floor_accuracy, 1) : "-");
    } else {
        c.assign(6, "n/a");
    }
    c.push_back(r->mean_map_distance_m ? Num(*r->mean_map_distance_m) : "-");
    if (m != Method::kEstimate) {
        c.push_back(Num(r->wall_s, 2));
        c.push_back(Num(r->poses_per_s, 0));
        c.push_back(r->verdict ? ToString(r->verdict->level) : "-");
    }
    if (m == Method::kDriftcorr) {
        c.push_back(r->covariance_in_95 ? Num(100.0 * *r->covariance_in_95, 1) : "-");
    }
    return c;
}

}  // namespace

std::string SummaryMarkdown(const std::vector<ScenarioEvaluation>& evals) {
    const std::vector<Method> cols = Columns(evals);
    std::ostringstream out;
    out << "# driftcorr eval\n\n"
        << "Horizontal errors against the ground truth, pose by pose, in the world East-North "
           "plane "
           "through the scenario's anchor, without re-alignment (docs/FORMAT.md, \"Judging\"). ATE "
           "= RMS "
           "error, final = error of the last pose, p90 = 90th percentile, drift = KITTI "
           "translational "
           "drift over 100-800 m segments, right floor = share of poses within 1.5 m of the ground "
           "truth's height (indoor3d), map = mean distance of the poses to the nearest road "
           "centre line, time = solver wall time (map field and loading excluded, shared by all "
           "methods).\n\n";
    std::vector<std::string> header = {"scenario", "mode", "poses", "ground truth"};
    for (const Method m : cols) {
        for (const std::string& h : MdMethodHeaders(m)) header.push_back(h);
    }
    out << "|";
    for (const std::string& h : header) out << " " << h << " |";
    out << "\n|";
    for (std::size_t i = 0; i < header.size(); ++i) out << (i < 2 ? "---|" : "---:|");
    out << "\n";
    std::vector<std::string> failures, warnings;
    for (const ScenarioEvaluation& ev : evals) {
        std::vector<std::string> row = {
            ev.label, ev.mode.empty() ? "?" : ev.mode, ev.ok() ? std::to_string(ev.poses) : "-",
            !ev.ok()              ? "-"
            : ev.has_ground_truth ? "yes"
                                  : "**no** (time and map distance only)"};
        if (!ev.ok()) {
            row.push_back("**FAILED**: " + ev.error);
            failures.push_back("- **" + ev.label + "**: " + ev.error);
        } else {
            for (const Method m : cols) {
                for (const std::string& c : MdMethodCells(ev, m)) row.push_back(c);
                const MethodResult* r = ev.Find(m);
                if (r && !r->ok)
                    failures.push_back("- **" + ev.label + "**, " + ToString(m) + ": " +
                                       r->message);
                if (!r) continue;
                for (const std::string& w : r->warnings) {
                    warnings.push_back("- **" + ev.label + "**, " + ToString(m) + ": " + w);
                }
            }
        }
        row.resize(header.size(), "");
        out << "|";
        for (const std::string& c : row) out << " " << MdCell(c) << " |";
        out << "\n";
    }
    out << "\n";
    if (!failures.empty()) {
        out << "## Failures\n\n";
        for (const std::string& f : failures) out << MdCell(f) << "\n";
        out << "\n";
    }
    if (!warnings.empty()) {
        out << "## Warnings\n\n";
        for (const std::string& w : warnings) out << MdCell(w) << "\n";
        out << "\n";
    }
    if (const double ratio = SpeedRatioPaperOverDriftcorr(evals); ratio > 0.0) {
        out << "## Speed\n\nPaper's method / driftcorr solver time, summed over the scenarios "
               "where "
               "both ran: **"
            << Num(ratio, 2) << "** ("
            << (ratio > 1.0 ? "driftcorr is faster" : "the paper's method is faster") << ").\n\n";
    }
    out << "## Plots\n\n";
    for (const ScenarioEvaluation& ev : evals) {
        if (!ev.ok()) continue;
        out << "- " << ev.label << ": [map](" << PlotName(ev, "map") << ")";
        if (ev.has_ground_truth)
            out << ", [error against distance](" << PlotName(ev, "error") << ")";
        out << "\n";
    }
    return out.str();
}

// ---- results.json ---------------------------------------------------------------------------

std::string ResultsJson(const std::vector<ScenarioEvaluation>& evals) {
    std::ostringstream o;
    bool any_failed = false;
    o << "{\n  \"scenarios\": [";
    for (std::size_t k = 0; k < evals.size(); ++k) {
        const ScenarioEvaluation& ev = evals[k];
        any_failed = any_failed || ev.AnyFailed();
        o << (k ? ",\n" : "\n") << "    {\n"
          << "      \"label\": " << JsonString(ev.label) << ",\n"
          << "      \"path\": " << JsonString(ev.path) << ",\n"
          << "      \"name\": " << JsonString(ev.name) << ",\n"
          << "      \"mode\": " << JsonString(ev.mode) << ",\n"
          << "      \"status\": " << JsonString(ev.ok() ? "ok" : "failed") << ",\n"
          << "      \"error\": " << (ev.ok() ? "null" : JsonString(ev.error)) << ",\n"
          << "      \"has_ground_truth\": " << (ev.has_ground_truth ? "true" : "false") << ",\n"
          << "      \"poses\": " << ev.poses << ",\n"
          << "      \"load_s\": " << JsonNum(ev.load_s) << ",\n"
          << "      \"map_s\": " << JsonNum(ev.map_s) << ",\n"
          << "      \"methods\": {";
        for (std::size_t j = 0; j < ev.methods.size(); ++j) {
            const MethodResult& r = ev.methods[j];
            o << (j ? ",\n" : "\n") << "        " << JsonString(ToString(r.method)) << ": {"
              << "\"ok\": " << (r.ok ? "true" : "false")
              << ", \"message\": " << JsonString(r.message) << ", \"wall_s\": " << JsonNum(r.wall_s)
              << ", \"poses_per_s\": " << JsonNum(r.poses_per_s) << ", \"mean_map_distance_m\": "
              << (r.mean_map_distance_m ? JsonNum(*r.mean_map_distance_m) : "null");
            if (r.verdict) {
                o << ", \"verdict\": " << JsonString(ToString(r.verdict->level))
                  << ", \"verdict_reasons\": [";
                for (std::size_t q = 0; q < r.verdict->reasons.size(); ++q) {
                    o << (q ? ", " : "") << JsonString(r.verdict->reasons[q]);
                }
                o << "]";
            }
            if (r.covariance_in_95) o << ", \"covariance_in_95\": " << JsonNum(*r.covariance_in_95);
            if (r.metrics) {
                const ErrorMetrics& m = *r.metrics;
                o << ", \"ate_m\": " << JsonNum(m.ate_m) << ", \"final_m\": " << JsonNum(m.final_m)
                  << ", \"max_m\": " << JsonNum(m.max_m) << ", \"p90_m\": " << JsonNum(m.p90_m)
                  << ", \"mean_m\": " << JsonNum(m.mean_m)
                  << ", \"drift_pct\": " << JsonNum(m.drift_pct)
                  << ", \"path_length_m\": " << JsonNum(m.path_length_m);
                if (ev.mode == "indoor3d")
                    o << ", \"floor_accuracy\": " << JsonNum(m.floor_accuracy);
            }
            o << "}";
        }
        o << (ev.methods.empty() ? "}" : "\n      }") << ",\n      \"plots\": {";
        if (ev.ok()) {
            o << "\"map\": " << JsonString(PlotName(ev, "map"));
            if (ev.has_ground_truth) o << ", \"error\": " << JsonString(PlotName(ev, "error"));
        }
        o << "}\n    }";
    }
    o << (evals.empty() ? "],\n" : "\n  ],\n");
    const double ratio = SpeedRatioPaperOverDriftcorr(evals);
    o << "  \"speed_ratio_paper_over_driftcorr\": " << (ratio > 0.0 ? JsonNum(ratio) : "null")
      << ",\n"
      << "  \"any_failed\": " << (any_failed ? "true" : "false") << "\n}\n";
    return o.str();
}

// ---- map plot -------------------------------------------------------------------------------

std::string MapSvg(const ScenarioEvaluation& ev) {
    // View box in metres: every track, padded.
    Eigen::AlignedBox2d box;
    if (ev.ground_truth) {
        for (const auto& p : ev.ground_truth->p_en) box.extend(p);
    }
    for (const MethodResult& r : ev.methods) {
        for (const auto& p : r.trajectory.p_en) box.extend(p);
    }
    if (box.isEmpty()) box.extend(Eigen::Vector2d::Zero());
    const double pad = 0.05 * box.sizes().maxCoeff() + 20.0;
    box.min() -= Eigen::Vector2d(pad, pad);
    box.max() += Eigen::Vector2d(pad, pad);
    const double max_w = 1000.0, max_h = 800.0, m = 10.0, top = 36.0;
    const double scale = std::min(max_w / box.sizes().x(), max_h / box.sizes().y());  // px per m
    const double w = box.sizes().x() * scale, h = box.sizes().y() * scale;
    auto to_px = [&](const Eigen::Vector2d& p) {
        return Eigen::Vector2d(m + (p.x() - box.min().x()) * scale,
                               top + (box.max().y() - p.y()) * scale);
    };
    std::ostringstream s;
    s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << Num(w + 2 * m, 0) << "\" height=\""
      << Num(h + top + m, 0) << "\" font-family=\"sans-serif\" font-size=\"13\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << m << "\" y=\"22\" font-size=\"15\" font-weight=\"bold\">"
      << XmlEscape(ev.label + (ev.name.empty() ? "" : " (" + ev.name + ")")) << "</text>\n"
      << "<defs><clipPath id=\"plot\"><rect x=\"" << m << "\" y=\"" << top << "\" width=\""
      << Num(w, 1) << "\" height=\"" << Num(h, 1) << "\"/></clipPath></defs>\n"
      << "<rect x=\"" << m << "\" y=\"" << top << "\" width=\"" << Num(w, 1) << "\" height=\""
      << Num(h, 1) << "\" fill=\"#fafafa\" stroke=\"#888\"/>\n<g clip-path=\"url(#plot)\">\n";
    // Roads at their width, light grey.
    s << "<g fill=\"none\" stroke=\"#d4d4d4\" stroke-linecap=\"round\" "
         "stroke-linejoin=\"round\">\n";
    for (const RoadPolyline& road : ev.network.roads) {
        Eigen::AlignedBox2d rb;
        for (const auto& p : road.points_en) rb.extend(p);
        if (!rb.intersects(box) || road.points_en.size() < 2) continue;
        s << "<polyline stroke-width=\"" << Num(std::max(1.5, 2.0 * road.half_width_m * scale), 1)
          << "\" points=\"" << PolylinePoints(road.points_en, to_px, 1.0) << "\"/>\n";
    }
    s << "</g>\n";
    // Tracks: ground truth below, methods above, ours last.
    if (ev.ground_truth) {
        s << "<polyline fill=\"none\" stroke=\"#000\" stroke-width=\"3\" stroke-linejoin=\"round\" "
             "points=\""
          << PolylinePoints(ev.ground_truth->p_en, to_px) << "\"/>\n";
    }
    for (const MethodResult& r : ev.methods) {
        if (!r.ok) continue;
        s << "<polyline fill=\"none\" stroke=\"" << MethodColour(r.method)
          << "\" stroke-width=\"1.6\" stroke-linejoin=\"round\" points=\""
          << PolylinePoints(r.trajectory.p_en, to_px) << "\"/>\n";
    }
    if (!ev.methods.empty() && !ev.methods[0].trajectory.p_en.empty()) {
        const Eigen::Vector2d st = to_px(ev.methods[0].trajectory.p_en[0]);
        s << "<circle cx=\"" << Num(st.x(), 1) << "\" cy=\"" << Num(st.y(), 1)
          << "\" r=\"5\" fill=\"none\" stroke=\"#000\" stroke-width=\"1.5\"/>\n";
    }
    s << "</g>\n";
    // Legend (top left) with the ATE of each method.
    std::vector<std::pair<std::string, std::string>> legend;
    legend.push_back(
        {"#d4d4d4", ev.mode == "indoor3d" ? "walkways of the walk's floor (map)" : "roads (map)"});
    if (ev.ground_truth) legend.push_back({"#000", "ground truth (start: circle)"});
    for (const MethodResult& r : ev.methods) {
        std::string text = ToString(r.method);
        if (!r.ok)
            text += ": failed";
        else if (r.metrics)
            text += ", ATE " + Num(r.metrics->ate_m, 1) + " m";
        legend.push_back({MethodColour(r.method), text});
    }
    const double lx = m + 8, ly = top + 8, lh = 20.0 * legend.size() + 8;
    s << "<rect x=\"" << lx << "\" y=\"" << ly << "\" width=\"230\" height=\"" << lh
      << "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#888\"/>\n";
    for (std::size_t i = 0; i < legend.size(); ++i) {
        const double y = ly + 16 + 20.0 * i;
        s << "<line x1=\"" << lx + 8 << "\" y1=\"" << y - 4 << "\" x2=\"" << lx + 34 << "\" y2=\""
          << y - 4 << "\" stroke=\"" << legend[i].first << "\" stroke-width=\"" << (i == 0 ? 6 : 3)
          << "\"/>\n"
          << "<text x=\"" << lx + 42 << "\" y=\"" << y << "\">" << XmlEscape(legend[i].second)
          << "</text>\n";
    }
    // Scale bar (bottom left) and north arrow (top right).
    const double bar_m = NiceStep(0.2 * box.sizes().x(), 1);
    const double bx = m + 14, by = top + h - 16, bw = bar_m * scale;
    s << "<rect x=\"" << bx - 6 << "\" y=\"" << by - 22 << "\" width=\"" << Num(bw + 12, 1)
      << "\" height=\"32\" fill=\"white\" fill-opacity=\"0.85\"/>\n"
      << "<path d=\"M" << bx << "," << by - 5 << " v5 h" << Num(bw, 1)
      << " v-5\" fill=\"none\" stroke=\"#000\" stroke-width=\"2\"/>\n"
      << "<text x=\"" << Num(bx + bw / 2, 1) << "\" y=\"" << by - 9 << "\" text-anchor=\"middle\">"
      << Num(bar_m, 0) << " m</text>\n";
    const double nx = m + w - 24, ny = top + 14;
    s << "<path d=\"M" << nx << "," << ny << " l-7,18 l7,-5 l7,5 z\" fill=\"#000\"/>\n"
      << "<text x=\"" << nx << "\" y=\"" << ny + 32 << "\" text-anchor=\"middle\">N</text>\n";
    s << "</svg>\n";
    return s.str();
}

// ---- error plot -----------------------------------------------------------------------------

std::string ErrorSvg(const ScenarioEvaluation& ev) {
    const double W = 900, H = 420, ml = 70, mr = 20, mt = 40, mb = 55;
    const double pw = W - ml - mr, ph = H - mt - mb;
    const double x_max = std::max(1.0, ev.distance_m.empty() ? 1.0 : ev.distance_m.back());
    double y_max = 0.0;
    for (const MethodResult& r : ev.methods) {
        for (const double e : r.errors_m) y_max = std::max(y_max, e);
    }
    const double x_step = NiceStep(x_max, 8), y_step = NiceStep(std::max(y_max, 1e-3), 6);
    const double x_top = std::ceil(x_max / x_step - 1e-9) * x_step;
    const double y_top = std::max(y_step, std::ceil(y_max / y_step - 1e-9) * y_step);
    auto to_px = [&](const Eigen::Vector2d& p) {
        return Eigen::Vector2d(ml + p.x() / x_top * pw, mt + ph - p.y() / y_top * ph);
    };
    std::ostringstream s;
    s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
      << "\" font-family=\"sans-serif\" font-size=\"13\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << ml << "\" y=\"24\" font-size=\"15\" font-weight=\"bold\">"
      << XmlEscape(ev.label + ": horizontal error against distance travelled") << "</text>\n";
    // Grid, ticks and tick labels.
    s << "<g stroke=\"#e0e0e0\">\n";
    for (double x = 0; x <= x_top + 1e-9; x += x_step) {
        const double px = to_px({x, 0}).x();
        s << "<line x1=\"" << Num(px, 1) << "\" y1=\"" << mt << "\" x2=\"" << Num(px, 1)
          << "\" y2=\"" << mt + ph << "\"/>\n";
    }
    for (double y = 0; y <= y_top + 1e-9; y += y_step) {
        const double py = to_px({0, y}).y();
        s << "<line x1=\"" << ml << "\" y1=\"" << Num(py, 1) << "\" x2=\"" << ml + pw << "\" y2=\""
          << Num(py, 1) << "\"/>\n";
    }
    s << "</g>\n<g>\n";
    const int xd = x_step < 1 ? 1 : 0, yd = y_step < 0.1 ? 2 : y_step < 1 ? 1 : 0;
    for (double x = 0; x <= x_top + 1e-9; x += x_step) {
        const double px = to_px({x, 0}).x();
        s << "<line x1=\"" << Num(px, 1) << "\" y1=\"" << mt + ph << "\" x2=\"" << Num(px, 1)
          << "\" y2=\"" << mt + ph + 5 << "\" stroke=\"#000\"/><text x=\"" << Num(px, 1)
          << "\" y=\"" << mt + ph + 19 << "\" text-anchor=\"middle\">" << Num(x, xd) << "</text>\n";
    }
    for (double y = 0; y <= y_top + 1e-9; y += y_step) {
        const double py = to_px({0, y}).y();
        s << "<line x1=\"" << ml - 5 << "\" y1=\"" << Num(py, 1) << "\" x2=\"" << ml << "\" y2=\""
          << Num(py, 1) << "\" stroke=\"#000\"/><text x=\"" << ml - 8 << "\" y=\"" << Num(py + 4, 1)
          << "\" text-anchor=\"end\">" << Num(y, yd) << "</text>\n";
    }
    s << "</g>\n<rect x=\"" << ml << "\" y=\"" << mt << "\" width=\"" << pw << "\" height=\"" << ph
      << "\" fill=\"none\" stroke=\"#000\"/>\n"
      << "<text x=\"" << ml + pw / 2 << "\" y=\"" << H - 12 << "\" text-anchor=\"middle\">"
      << "distance travelled along the ground truth [m]</text>\n"
      << "<text transform=\"translate(18," << mt + ph / 2
      << ") rotate(-90)\" text-anchor=\"middle\">"
      << "horizontal error [m]</text>\n";
    // The uncertainty band of a method with per-pose covariance: from 0 to the radius of the
    // circle around the larger axis of each pose's 95 % ellipse, sqrt(5.991 * lambda_max).
    for (const MethodResult& r : ev.methods) {
        if (!r.ok || r.covariance.size() != ev.distance_m.size()) continue;
        std::vector<Eigen::Vector2d> band;
        for (std::size_t i = 0; i < r.covariance.size(); ++i) {
            const Eigen::Matrix2d& c = r.covariance[i].xy_m2;
            const double half_trace = 0.5 * c.trace();
            const double lambda_max =
                half_trace + std::sqrt(std::max(0.0, half_trace * half_trace - c.determinant()));
            band.emplace_back(ev.distance_m[i], std::min(y_top, std::sqrt(5.991 * lambda_max)));
        }
        band.emplace_back(ev.distance_m.back(), 0.0);
        band.emplace_back(ev.distance_m.front(), 0.0);
        s << "<polygon fill=\"" << MethodColour(r.method) << "\" fill-opacity=\"0.15\" "
          << "stroke=\"none\" points=\"" << PolylinePoints(band, to_px, 0.5) << "\"/>\n";
    }
    // One line per method.
    for (const MethodResult& r : ev.methods) {
        if (!r.ok || r.errors_m.size() != ev.distance_m.size()) continue;
        std::vector<Eigen::Vector2d> pts;
        pts.reserve(r.errors_m.size());
        for (std::size_t i = 0; i < r.errors_m.size(); ++i)
            pts.emplace_back(ev.distance_m[i], r.errors_m[i]);
        s << "<polyline fill=\"none\" stroke=\"" << MethodColour(r.method)
          << "\" stroke-width=\"1.6\" stroke-linejoin=\"round\" points=\""
          << PolylinePoints(pts, to_px, 0.5) << "\"/>\n";
    }
    // Legend, top left inside the plot.
    double ly = mt + 8;
    s << "<rect x=\"" << ml + 8 << "\" y=\"" << ly << "\" width=\"290\" height=\""
      << 20 * ev.methods.size() + 8
      << "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#888\"/>\n";
    for (const MethodResult& r : ev.methods) {
        ly += 20;
        std::string text = ToString(r.method);
        if (!r.ok)
            text += ": failed";
        else if (r.metrics)
            text += ", final " + Num(r.metrics->final_m, 1) + " m";
        if (r.ok && !r.covariance.empty()) text += " (band: 95 %)";
        s << "<line x1=\"" << ml + 16 << "\" y1=\"" << ly - 4 << "\" x2=\"" << ml + 42 << "\" y2=\""
          << ly - 4 << "\" stroke=\"" << MethodColour(r.method)
          << "\" stroke-width=\"3\"/><text x=\"" << ml + 50 << "\" y=\"" << ly << "\">"
          << XmlEscape(text) << "</text>\n";
    }
    s << "</svg>\n";
    return s.str();
}

// ---- files ----------------------------------------------------------------------------------

std::vector<std::string> WriteReport(const std::string& report_dir,
                                     const std::vector<ScenarioEvaluation>& evals) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::create_directories(report_dir, ec);
    if (!fs::is_directory(report_dir)) {
        throw std::runtime_error(report_dir + ": cannot create the report folder" +
                                 (ec ? ": " + ec.message() : std::string()));
    }
    std::vector<std::string> written;
    auto write = [&](const std::string& name, const std::string& text) {
        const std::string path = (fs::path(report_dir) / name).string();
        AtomicFile f(path);
        f.stream() << text;
        f.Commit();
        written.push_back(path);
    };
    auto plot = [&](const std::string& name, const std::string& svg) {
        write(name, svg);
        write(name.substr(0, name.size() - 4) + ".png", SvgToPng(svg));
    };
    for (const ScenarioEvaluation& ev : evals) {
        if (!ev.ok()) continue;
        plot(PlotName(ev, "map"), MapSvg(ev));
        if (ev.has_ground_truth) plot(PlotName(ev, "error"), ErrorSvg(ev));
    }
    write("results.json", ResultsJson(evals));
    write("summary.md", SummaryMarkdown(evals));
    return written;
}

}  // namespace driftcorr::eval
