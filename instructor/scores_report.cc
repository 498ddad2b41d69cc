#include "instructor/scores_report.h"

#include <sys/stat.h>
#include <sys/wait.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

#include "common/scores/scores_store.h"

namespace microdex::instructor {
namespace {

// A name usable in a file name: letters, digits, '-', '_' and '.'; anything else '_'.
std::string FileSafe(const std::string& s) {
  std::string out;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    out += ok ? c : '_';
  }
  return out.empty() ? "_" : out;
}

// gnuplot's single-quoted string: a quote doubled.
std::string GnuplotQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

void MakeDir(const std::string& dir) {
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) {
    throw std::runtime_error(dir + ": cannot create the folder");
  }
}

std::ofstream OpenOut(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write");
  return f;
}

// Runs gnuplot on the script; throws naming the script when it fails or is missing.
void RunGnuplot(const std::string& script, const std::string& png) {
  const std::string cmd = "gnuplot " + GnuplotQuote(script) + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) throw std::runtime_error(script + ": cannot run gnuplot");
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int status = ::pclose(p);
  if (status != 0) {
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127) {
      throw std::runtime_error("gnuplot not found (Debian: gnuplot-nox; deploy/install-deps)");
    }
    while (!out.empty() && out.back() == '\n') out.pop_back();
    throw std::runtime_error(script + ": gnuplot failed: " + out);
  }
  struct stat st {};
  if (::stat(png.c_str(), &st) != 0 || st.st_size == 0) {
    throw std::runtime_error(script + ": gnuplot wrote no " + png);
  }
}

std::string Fmt(double v, int digits = 1) {
  if (!std::isfinite(v)) return "–";
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

}  // namespace

std::vector<std::string> WriteLearningCurves(scores::ScoresDb& db, const std::string& course,
                                             const std::string& dir) {
  const auto sessions = scores::LoadScoredSessions(db, course);
  if (sessions.empty()) {
    throw std::runtime_error(db.name() + ": no scored session" +
                             (course.empty() ? "" : " in course '" + course + "'"));
  }
  MakeDir(dir);
  // trainee → its sessions in start order (LoadScoredSessions sorts them so).
  std::map<std::string, std::vector<const scores::ScoredSession*>> by_trainee;
  for (const auto& s : sessions) by_trainee[s.trainee].push_back(&s);
  std::vector<std::string> files;
  for (const auto& [trainee, list] : by_trainee) {
    const std::string stem = dir + "/curve_" + FileSafe(trainee);
    // One data block per scene: session number (across all the trainee's sessions), score.
    std::map<std::string, std::vector<std::pair<int, double>>> by_scene;
    for (std::size_t i = 0; i < list.size(); ++i) {
      by_scene[list[i]->scene].emplace_back(static_cast<int>(i + 1), list[i]->score);
    }
    {
      std::ofstream dat = OpenOut(stem + ".dat");
      dat << "# session score  (one block per scene: " << trainee << ")\n";
      for (const auto& [scene, points] : by_scene) {
        dat << "# " << scene << "\n";
        for (const auto& [n, score] : points) dat << n << " " << score << "\n";
        dat << "\n\n";
      }
    }
    {
      std::ofstream gp = OpenOut(stem + ".gp");
      gp << "set terminal pngcairo size 900,560 font 'sans,11'\n"
         << "set output " << GnuplotQuote(stem + ".png") << "\n"
         << "set title " << GnuplotQuote("learning curve: " + trainee) << " noenhanced\n"
         << "set xlabel 'session'\nset ylabel 'score'\nset yrange [0:100]\n"
         << "set xrange [0.5:" << list.size() + 0.5 << "]\nset grid\nset key bottom right "
         << "noenhanced\nset xtics 1\n"
         << "plot ";
      int index = 0;
      for (const auto& [scene, points] : by_scene) {
        gp << (index ? ", \\\n     " : "") << GnuplotQuote(stem + ".dat") << " index " << index
           << " using 1:2 with linespoints lw 2 pt 7 title " << GnuplotQuote(scene);
        ++index;
      }
      gp << "\n";
    }
    RunGnuplot(stem + ".gp", stem + ".png");
    files.push_back(stem + ".png");
  }
  return files;
}

ExperimentReport WriteExperimentReport(scores::ScoresDb& db, const std::string& experiment,
                                       const std::string& dir) {
  const scores::ExperimentRow e = scores::LoadExperiment(db, experiment);
  const auto sessions = scores::LoadScoredSessions(db, "", experiment);
  ExperimentReport r;
  r.experiment = experiment;
  r.trials = e.trials_per_trainee;
  r.outcome_from_trial = r.trials >= 2 ? r.trials / 2 + 1 : 1;
  // condition → trainee → trial → final score (a trial without a final score is left out).
  std::map<std::string, std::map<std::string, std::map<int, double>>> scores;
  int finals = 0, unfinished = 0;
  for (const auto& s : sessions) {
    if (s.trial <= 0) continue;  // a void trial (ended without a final score), run again
    if (!s.is_final) {
      ++unfinished;
      continue;
    }
    scores[s.condition][s.trainee][s.trial] = s.score;
    ++finals;
  }
  if (finals == 0) {
    throw std::runtime_error(db.name() + ": experiment '" + experiment +
                             "' has no trial with a final score yet");
  }
  std::map<std::string, std::vector<double>> outcomes;  // condition → per-trainee outcome
  for (const auto& c : e.conditions) {
    ConditionCurve curve;
    curve.condition = c.name;
    curve.cues = c.cues.empty() ? "(none)" : c.cues;
    const auto& trainees = scores[c.name];
    curve.trainees = static_cast<int>(trainees.size());
    for (int trial = 1; trial <= r.trials; ++trial) {
      std::vector<double> v;
      for (const auto& [trainee, by_trial] : trainees) {
        if (auto it = by_trial.find(trial); it != by_trial.end()) v.push_back(it->second);
      }
      curve.by_trial.push_back(scores::CalcMeanCi(v));
    }
    for (const auto& [trainee, by_trial] : trainees) {
      double sum = 0;
      int n = 0;
      for (const auto& [trial, score] : by_trial) {
        if (trial >= r.outcome_from_trial) {
          sum += score;
          ++n;
        }
      }
      if (n > 0) outcomes[c.name].push_back(sum / n);
    }
    curve.outcome = scores::CalcMeanCi(outcomes[c.name]);
    r.conditions.push_back(std::move(curve));
  }
  double best = -INFINITY;
  for (const auto& c : r.conditions) {
    if (c.outcome.n > 0 && c.outcome.mean > best) {
      best = c.outcome.mean;
      r.best = c.condition;
    }
  }
  for (std::size_t i = 0; i < r.conditions.size(); ++i) {
    for (std::size_t j = i + 1; j < r.conditions.size(); ++j) {
      ConditionContrast k;
      k.a = r.conditions[i].condition;
      k.b = r.conditions[j].condition;
      k.effect = scores::CalcHedgesG(outcomes[k.a], outcomes[k.b]);
      k.mean_difference = r.conditions[i].outcome.mean - r.conditions[j].outcome.mean;
      r.contrasts.push_back(k);
    }
  }

  MakeDir(dir);
  const std::string stem = dir + "/experiment_" + FileSafe(experiment);
  {
    std::ofstream csv = OpenOut(stem + "_trials.csv");
    csv << "session,trainee,condition,trial,is_final,score\n";
    for (const auto& s : sessions) {
      csv << s.id << "," << s.trainee << "," << s.condition << "," << s.trial << ","
          << (s.is_final ? 1 : 0) << "," << Fmt(s.score, 4) << "\n";
    }
  }
  {
    std::ofstream dat = OpenOut(stem + ".dat");
    dat << "# trial mean lo hi n (one block per condition)\n";
    for (const auto& c : r.conditions) {
      dat << "# " << c.condition << "\n";
      for (std::size_t t = 0; t < c.by_trial.size(); ++t) {
        const auto& m = c.by_trial[t];
        if (m.n == 0) continue;
        dat << t + 1 << " " << m.mean << " " << m.lo << " " << m.hi << " " << m.n << "\n";
      }
      dat << "\n\n";
    }
  }
  {
    std::ofstream gp = OpenOut(stem + ".gp");
    gp << "set terminal pngcairo size 960,600 font 'sans,11'\n"
       << "set output " << GnuplotQuote(stem + ".png") << "\n"
       << "set title "
       << GnuplotQuote("experiment " + experiment +
                       ": score by trial, mean and 95 % confidence band")
       << " noenhanced\n"
       << "set xlabel 'trial'\nset ylabel 'score'\nset yrange [0:100]\nset grid\n"
       << "set xrange [0.8:" << r.trials + 0.2 << "]\nset xtics 1\nset key bottom right "
       << "noenhanced\nset style fill transparent solid 0.2 noborder\n"
       << "plot ";
    for (std::size_t i = 0; i < r.conditions.size(); ++i) {
      const std::string data = GnuplotQuote(stem + ".dat");
      gp << (i ? ", \\\n     " : "") << data << " index " << i
         << " using 1:3:4 with filledcurves lc " << i + 1 << " notitle, \\\n     " << data
         << " index " << i << " using 1:2 with linespoints lw 2 pt 7 lc " << i + 1 << " title "
         << GnuplotQuote(r.conditions[i].condition +
                         " (n = " + std::to_string(r.conditions[i].trainees) + ")");
    }
    gp << "\n";
  }
  RunGnuplot(stem + ".gp", stem + ".png");
  {
    std::ofstream md = OpenOut(stem + ".md");
    md << "# Experiment " << experiment << "\n\n"
       << "Scene `" << e.scene << "`, seed " << e.seed << ", " << r.trials
       << " trials per trainee, " << finals << " trials with a final score";
    if (unfinished) md << " (" << unfinished << " without one, left out)";
    md << ". Curves: `" << stem.substr(stem.rfind('/') + 1) << ".png`.\n\n"
       << "A trainee's outcome is the mean of its scores in trials " << r.outcome_from_trial
       << " to " << r.trials
       << "; a condition's outcome the mean of its trainees' (95 % CI: Student t).\n\n"
       << "| condition | cues | trainees | outcome | 95 % CI |";
    for (int t = 1; t <= r.trials; ++t) md << " trial " << t << " |";
    md << "\n|---|---|---|---|---|";
    for (int t = 1; t <= r.trials; ++t) md << "---|";
    md << "\n";
    for (const auto& c : r.conditions) {
      md << "| " << c.condition << " | " << c.cues << " | " << c.trainees << " | "
         << Fmt(c.outcome.mean) << " | " << Fmt(c.outcome.lo) << " – " << Fmt(c.outcome.hi) << " |";
      for (const auto& m : c.by_trial) md << " " << Fmt(m.mean) << " |";
      md << "\n";
    }
    md << "\n## Effect sizes\n\nHedges' g of the outcome (condition A against B), with its 95 % "
          "confidence interval (normal approximation, Hedges & Olkin 1985); a positive g: A "
          "scored higher.\n\n"
       << "| A | B | n A | n B | difference (points) | Hedges' g | 95 % CI |\n"
       << "|---|---|---|---|---|---|---|\n";
    for (const auto& k : r.contrasts) {
      md << "| " << k.a << " | " << k.b << " | " << k.effect.n1 << " | " << k.effect.n2 << " | "
         << Fmt(k.mean_difference) << " | " << Fmt(k.effect.g, 2) << " | " << Fmt(k.effect.lo, 2)
         << " – " << Fmt(k.effect.hi, 2) << " |\n";
    }
    md << "\nBest condition: " << r.best << "\n";
  }
  r.files = {stem + ".png", stem + ".md", stem + "_trials.csv"};
  return r;
}

}  // namespace microdex::instructor
