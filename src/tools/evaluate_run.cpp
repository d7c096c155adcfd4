// Evaluates one or more run_offline results files against the recording's ground truth: prints
// a short summary of each (objects found and true, pose error, contacts, interpenetration, time)
// and, with --json, writes the benchmark's evaluation file (docs/BENCHMARK.md) that
// bench_report.py turns into COCO mAP, precision and recall, ADD-S curves and the report.
//
//   evaluate_run --ground-truth SCENE_gt.yaml --results RESULTS.yaml [--json OUT.json]
//       [--model-set primitives|ycb_video|FILE.yaml] [--models DIR] [--no-vsd]
//       [--bop-dataset DIR [--bop-scene-id N]] [--quiet]
//
// --no-vsd: BOP's MSSD and MSPD only, not its VSD (two renders per estimate).
// --bop-dataset: also writes (or updates) the ground truth at the run's keyframes as a BOP dataset
// folder (evaluation/bop_dataset.h; scene --bop-scene-id, default 0, as run_offline's
// --bop-results), so that BOP's own toolkit scores the run's BOP results.
// The model set defaults to the one the ground truth names. Exit code 0, 1 when a file cannot be
// read or nothing can be compared, 2 for bad arguments.
#include "command_line.h"
#include "geofusion/estimation/run_results.h"
#include "geofusion/evaluation/bop_dataset.h"
#include "geofusion/evaluation/run_evaluation.h"
#include "geofusion/simulation/dataset.h"
#include "model_set_option.h"

#include <cstdio>
#include <iostream>
#include <string>

namespace {

struct Options {
  std::string ground_truth, results, json, model_set, models_dir, bop_dataset;
  int bop_scene_id = 0;
  bool quiet = false, no_vsd = false;
};

void usage() {
  std::cerr << "usage: evaluate_run --ground-truth SCENE_gt.yaml --results RESULTS.yaml\n"
               "         [--json OUT.json] [--model-set primitives|ycb_video|FILE.yaml]\n"
               "         [--models DIR] [--no-vsd] [--bop-dataset DIR [--bop-scene-id N]]\n"
               "         [--quiet]\n";
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--ground-truth", &o.ground_truth);
  args.value("--results", &o.results);
  args.value("--json", &o.json);
  args.value("--model-set", &o.model_set);
  args.value("--models", &o.models_dir);
  args.toggle("--quiet", &o.quiet);
  args.toggle("--no-vsd", &o.no_vsd);
  args.value("--bop-dataset", &o.bop_dataset);
  args.value("--bop-scene-id", &o.bop_scene_id);
  args.parse(argc, argv, usage);
  if (o.ground_truth.empty() || o.results.empty()) {
    throw std::runtime_error("--ground-truth and --results are required");
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
  Options opt;
  if (!geofusion::readCommandLine("evaluate_run", usage, [&] { opt = parse(argc, argv); }))
    return 2;
  const std::string set = opt.model_set.empty() ? modelSetOf(opt.ground_truth) : opt.model_set;
  ModelSet models;
  if (!loadModelSetOption("evaluate_run", set, opt.models_dir, &models)) return 1;
  GroundTruth gt;
  RunResults results;
  std::string error;
  if (!readGroundTruth(opt.ground_truth, models, &gt, &error) ||
      !readRunResults(opt.results, models, &results, &error)) {
    std::cerr << "evaluate_run: " << error << "\n";
    return 1;
  }
  RunEvaluation evaluation;
  EvaluationConfig config;
  config.vsd = !opt.no_vsd;
  if (!evaluateRun(gt, results, config, &evaluation, &error)) {
    std::cerr << "evaluate_run: " << opt.results << ": " << error << "\n";
    return 1;
  }
  if (!opt.json.empty() && !writeEvaluationJson(opt.json, evaluation, &error)) {
    std::cerr << "evaluate_run: " << error << "\n";
    return 1;
  }
  BopIds ids;
  ids.scene_id = opt.bop_scene_id;
  if (!opt.bop_dataset.empty() && !writeBopDataset(opt.bop_dataset, models, gt, results, ids,
                                                   config.stamp_tolerance_s, &error)) {
    std::cerr << "evaluate_run: --bop-dataset: " << error << "\n";
    return 1;
  }
  if (!opt.quiet) std::cout << summarize(evaluation);  // warnings included
  for (const std::string& w : evaluation.warnings)
    if (opt.quiet) std::cerr << "evaluate_run: warning: " << opt.results << ": " << w << "\n";
  return 0;
}
