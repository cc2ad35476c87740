// bench_pipeline: cost of the in-process grasping pipeline. Runs one Exp-2 set
// (front, middle, back of config/scenes/table_three_objects.yaml) and one Exp-3 set (forward,
// downward, sideways grasps of config/scenes/single_object.yaml) of every method of the protocol
// ("all", as make experiments runs them), on one thread, and prints one JSON line per protocol:
// sim seconds, process CPU seconds (load-independent: the real-time factor on one core), wall
// seconds and the 1-minute load average (wall figures depend on the machine's load), and wall
// seconds per sim second of every stage (image, depth, tags, grasps, obstacles, control,
// sequencer, physics; pipelineStageCosts). The camera renders only what perception consumes, at
// its rate (GraspPipeline::perceive): the counts of images (and of images skipped with no tag in
// view) and clouds are in the stage line.
#include "ehc_bringup/grasp_experiment.h"
#include "ehc_common/bench_util.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>

namespace {

void bench(const char* name, ehc_bringup::GraspProtocol protocol) {
  ehc_bringup::GraspExperimentParams p;
  p.protocol = protocol;
  p.config_dir = EHC_CONFIG_DIR;
  p.sets = 1;
  p.per_set = 1;
  p.jobs = 1;
  const ehc_bringup::GraspExperiment exp(p, ehc_bringup::graspMethodNames(protocol, "all"));
  const std::clock_t c0 = std::clock();
  const auto w0 = std::chrono::steady_clock::now();
  const ehc_bringup::GraspExperimentResult r = exp.run();
  const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  double load[1] = {0.0};
  if (getloadavg(load, 1) != 1) load[0] = -1.0;
  int ok = 0;
  for (const auto& t : r.trials) ok += t.success;
  using ehc_common::jsonNumber;
  ehc_common::Json line;
  line["grasps"] = r.trials.size();
  line["successes"] = ok;
  line["sim_s"] = jsonNumber(r.sim_time_s);
  line["cpu_s"] = jsonNumber(cpu);
  line["wall_s"] = jsonNumber(wall);
  line["load_1min"] = jsonNumber(load[0]);
  line["cpu_real_time_factor"] = jsonNumber(r.sim_time_s / std::max(1e-9, cpu));
  line["wall_real_time_factor"] = jsonNumber(r.sim_time_s / std::max(1e-9, wall));
  line["stages"] = ehc_common::Json::parse(ehc_bringup::pipelineStageCosts(r.counters, r.sim_time_s));
  ehc_common::benchPrintValues(name, line);
}

}  // namespace

int main() {
  try {
    bench("grasp_pipeline_exp2_set", ehc_bringup::GraspProtocol::Table);
    bench("grasp_pipeline_exp3_set", ehc_bringup::GraspProtocol::Poses);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_pipeline: %s\n", e.what());
    return 2;
  }
}
