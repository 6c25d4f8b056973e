// The reports of term selection: text for people, JSON for programs (docs/json.md, "select").

#include <cstdio>
#include <sstream>

#include "common/json.hpp"
#include "common/number.hpp"
#include "momentid/json.hpp"
#include "momentid/model.hpp"
#include "momentid/select.hpp"

namespace momentid {
namespace {

using Json = nlohmann::ordered_json;

// The candidates a subset keeps, by their terms: "y, y^3, v, x".
std::string kept_terms(const SelectResult& r, const std::vector<bool>& kept) {
  std::string out;
  for (std::size_t c = 0; c < r.candidates.size(); ++c) {
    if (kept[r.candidates[c]]) out += (out.empty() ? "" : ", ") + r.tests[c].terms;
  }
  return out.empty() ? "(none)" : out;
}

std::vector<std::string> kept_names(const SelectResult& r, const std::vector<bool>& kept,
                                    bool want) {
  std::vector<std::string> out;
  for (std::size_t c = 0; c < r.candidates.size(); ++c) {
    if (kept[r.candidates[c]] == want) out.push_back(r.tests[c].name);
  }
  return out;
}

std::string pvalue_text(double p) { return p < 1e-16 ? "<1e-16" : number(p, "%.2g"); }

// "0.502 +- 0.0068", or "(dropped)" for a parameter the result lacks.
std::string estimate_text(const IdentifyResult& r, const std::string& name) {
  for (const ParameterEstimate& p : r.parameters()) {
    if (p.name == name) {
      return number(p.estimate, "%.6g") +
             (p.fixed ? " fixed" : " +- " + number(p.std_error, "%.3g"));
    }
  }
  return "(dropped)";
}

// The selection's status, and when the structure is uncertain why, with the chosen and the
// runner-up's estimates side by side.
void status_text(std::ostream& out, const SelectResult& r) {
  out << "selection status: " << to_string(status(r));
  if (r.uncertain.empty()) {
    out << "\n";
    return;
  }
  out << ", the structure is uncertain (";
  for (std::size_t i = 0; i < r.uncertain.size(); ++i) out << (i ? "; " : "") << r.uncertain[i];
  out << "): compare the runner-up before using the chosen model\n";
  if (!r.runner_up) return;
  char line[512];
  std::snprintf(line, sizeof line, "  %-12s  %-28s  %s\n", "parameter", "chosen (rank 1)",
                "runner-up (rank 2)");
  out << line;
  for (const Declaration& p : r.library.model->parameters()) {
    const std::string chosen = estimate_text(r.chosen, p.name);
    const std::string runner_up = estimate_text(*r.runner_up, p.name);
    if (chosen == "(dropped)" && runner_up == "(dropped)") continue;
    std::snprintf(line, sizeof line, "  %-12s  %-28s  %s\n", p.name.c_str(), chosen.c_str(),
                  runner_up.c_str());
    out << line;
  }
  out << "  runner-up's status: " << to_string(status(*r.runner_up)) << "\n";
}

}  // namespace

std::string format_text(const SelectResult& r) {
  std::ostringstream out;
  const Model& model = *r.library.model;
  out << "term selection for model " << model.name() << " on " << r.library.data_name << "\n";
  out << "  candidates: " << r.candidates.size() << " of " << model.parameters().size()
      << " parameters; "
      << (r.exhaustive ? "every subset scored (" + std::to_string(r.scored) + ")"
                       : "backward elimination (" + std::to_string(r.scored) + " subsets scored)")
      << "\n  criterion: J" << (r.dispersion > 1 ? " / " + number(r.dispersion, "%.3g") : "")
      << " + " << number(r.penalty, "%.4g")
      << " per candidate kept (ln T, T = " << r.library.estimate.intervals
      << " sample intervals), J calibrated as the J test is, on the library's fixed weighting\n\n";
  char line[512];
  std::snprintf(line, sizeof line, "  %4s  %10s  %9s  %10s  %4s  %8s  %s\n", "rank", "criterion",
                "behind", "J", "dof", "p(J)", "candidates kept");
  out << line;
  for (std::size_t i = 0; i < r.ranking.size(); ++i) {
    const SelectResult::Subset& s = r.ranking[i];
    std::snprintf(line, sizeof line, "  %4zu  %10s  %9s  %10s  %4d  %8s  %s\n", i + 1,
                  number(s.criterion, "%.5g").c_str(),
                  number(s.criterion - r.ranking[0].criterion, "%.3g").c_str(),
                  number(s.j, "%.5g").c_str(), s.dof, pvalue_text(s.pvalue).c_str(),
                  kept_terms(r, s.kept).c_str());
    out << line;
  }
  out << "\ncandidates at the chosen subset (J without less J with"
      << (r.dispersion > 1 ? ", divided by " + number(r.dispersion, "%.3g") : "")
      << ", chi-square with 1 dof when the parameter is 0)\n";
  std::size_t width = 9, term_width = 4;
  for (const auto& t : r.tests) {
    width = std::max(width, t.name.size());
    term_width = std::max(term_width, t.terms.size());
  }
  std::snprintf(line, sizeof line, "  %-*s  %-*s  %-7s  %10s  %8s\n", static_cast<int>(width),
                "candidate", static_cast<int>(term_width), "term", "chosen", "J change", "p");
  out << line;
  for (const auto& t : r.tests) {
    std::snprintf(line, sizeof line, "  %-*s  %-*s  %-7s  %10s  %8s\n", static_cast<int>(width),
                  t.name.c_str(), static_cast<int>(term_width), t.terms.c_str(),
                  t.kept ? "kept" : "dropped", number(t.difference, "%.4g").c_str(),
                  pvalue_text(t.pvalue).c_str());
    out << line;
  }
  out << "\nlag windows (the same pass, the library's instruments)\n";
  for (const SelectResult::Window& w : r.windows) {
    out << "  lags " << w.first_lag << ".." << w.last_lag << ": " << kept_terms(r, w.kept) << "\n";
  }
  if (!r.validated.empty()) {
    out << "\nvalidation on " << r.validation_name
        << " (each subset identified on the record above, simulated through its inputs)\n";
    for (const SelectResult::Validated& v : r.validated) {
      out << "  rank " << v.rank + 1 << ":";
      if (!v.failed.empty()) out << " not validated (" << v.failed << ")";
      for (const auto& o : v.outputs) {
        out << " " << o.name << " fit " << number(o.fit, "%.2f") << "% (rms "
            << number(o.rms, "%.4g") << ")";
      }
      out << (v.consistent || !v.failed.empty() ? "" : ", inconsistent (see validate)") << "  "
          << kept_terms(r, r.ranking[v.rank].kept) << "\n";
    }
  }
  out << "\n";
  if (r.warnings.empty()) out << "selection warnings: none\n";
  for (const std::string& w : r.warnings) out << "selection warning: " << w << "\n";
  status_text(out, r);
  out << "\nthe chosen model, identified on its own equations\n\n" << format_text(r.chosen);
  return out.str();
}

nlohmann::ordered_json json_value(const SelectResult& r) {
  Json out = json_value(r.chosen);
  const std::vector<bool>& best = r.ranking.front().kept;
  out["selected"] = kept_names(r, best, true);
  out["dropped"] = kept_names(r, best, false);
  Json ranking = Json::array();
  for (const SelectResult::Subset& s : r.ranking) {
    ranking.push_back({{"selected", kept_names(r, s.kept, true)},
                       {"criterion", json_value(s.criterion)},
                       {"j", json_value(s.j)},
                       {"dof", s.dof},
                       {"pvalue", json_value(s.pvalue)}});
  }
  Json tests = Json::array();
  for (const auto& t : r.tests) {
    tests.push_back({{"candidate", t.name},
                     {"terms", t.terms},
                     {"kept", t.kept},
                     {"j_change", json_value(t.difference)},
                     {"pvalue", json_value(t.pvalue)}});
  }
  Json windows = Json::array();
  for (const SelectResult::Window& w : r.windows) {
    windows.push_back(
        {{"lags", {w.first_lag, w.last_lag}}, {"selected", kept_names(r, w.kept, true)}});
  }
  Json validated = Json::array();
  for (const SelectResult::Validated& v : r.validated) {
    Json fits = Json::object();
    for (const auto& o : v.outputs) {
      fits[o.name] = {{"fit", json_value(o.fit)}, {"rms", json_value(o.rms)}};
    }
    validated.push_back({{"rank", v.rank + 1},
                         {"selected", kept_names(r, r.ranking[v.rank].kept, true)},
                         {"outputs", fits},
                         {"consistent", v.consistent}});
    if (!v.failed.empty()) validated.back()["failed"] = v.failed;
  }
  out["diagnostics"]["status"] = to_string(status(r));
  Json runner_up;
  if (r.runner_up) {
    runner_up = {{"selected", kept_names(r, r.ranking[1].kept, true)},
                 {"status", to_string(status(*r.runner_up))},
                 {"parameters", json_value(*r.runner_up)["parameters"]}};
  }
  out["selection"] = {{"status", to_string(status(r))},
                      {"uncertain", r.uncertain},
                      {"runner_up", runner_up},
                      {"search", r.exhaustive ? "exhaustive" : "backward"},
                      {"scored", r.scored},
                      {"penalty", json_value(r.penalty)},
                      {"dispersion", json_value(r.dispersion)},
                      {"ranking", ranking},
                      {"tests", tests},
                      {"windows", windows},
                      {"warnings", r.warnings}};
  if (!r.validated.empty()) {
    out["selection"]["validation"] = {{"data", r.validation_name}, {"subsets", validated}};
  }
  return out;
}

std::string format_json(const SelectResult& r) { return json_text(json_value(r)); }

}  // namespace momentid
