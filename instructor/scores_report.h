#pragma once
// Reports from the scores database (microdex-replay --db URL ...): learning curves per
// trainee across sessions, and the report of a cue experiment (per-condition learning curves
// with 95 % confidence bands, effect sizes between conditions). PNGs are drawn by gnuplot
// (pngcairo); the data each plot shows is written beside it (.dat), the tables as Markdown.

#include <string>
#include <vector>

#include "common/scores/scores_db.h"
#include "common/scores/stats.h"

namespace microdex::instructor {

// One PNG per trainee, DIR/curve_TRAINEE.png: score against the trainee's session number, one
// line per scene (course "": every course). Returns the files written. Throws
// std::runtime_error (no scored session, DIR not writable, gnuplot missing or failing).
std::vector<std::string> WriteLearningCurves(scores::ScoresDb& db, const std::string& course,
                                             const std::string& dir);

struct ConditionCurve {
  std::string condition;
  std::string cues;
  int trainees = 0;
  std::vector<scores::MeanCi> by_trial;  // trial 1..T: score over the condition's trainees
  scores::MeanCi outcome;                // of the trainees' outcomes (below)
};

struct ConditionContrast {
  std::string a, b;  // condition a against condition b
  scores::EffectSize effect;
  double mean_difference = 0;  // outcome a − b, score points
};

struct ExperimentReport {
  std::string experiment;
  int trials = 0;
  int outcome_from_trial = 1;  // a trainee's outcome: mean score of trials from this one on
  std::vector<ConditionCurve> conditions;
  std::vector<ConditionContrast> contrasts;  // every pair, in condition order
  std::string best;                          // the condition with the highest mean outcome
  std::vector<std::string> files;
};

// DIR/experiment_NAME.png (per-condition curves, mean and 95 % band by trial),
// DIR/experiment_NAME.md (the tables) and DIR/experiment_NAME_trials.csv (every scored trial).
// The outcome of a trainee is the mean of its final scores over the last half of the trials
// (trials ⌊T/2⌋+1 .. T; trial 1 when T = 1): where a learning rate shows. Throws
// std::runtime_error / ScoresDbError.
ExperimentReport WriteExperimentReport(scores::ScoresDb& db, const std::string& experiment,
                                       const std::string& dir);

}  // namespace microdex::instructor
