// bench_pipeline: cost of the in-process grasping pipeline (issue 14 item 6). Runs one Exp-3 set
// (ehc: forward, downward, sideways grasps of config/scenes/single_object.yaml) on one thread and
// prints one JSON line: sim seconds, process CPU seconds (load-independent: the real-time factor
// on one core), wall seconds (depends on the machine's load), and wall seconds per sim second of
// every stage (render, tags, grasps, obstacles, control, sequencer, physics).
#include "ehc_bringup/grasp_experiment.h"

#include <chrono>
#include <cstdio>
#include <ctime>

int main() {
  try {
    ehc_bringup::GraspExperimentParams p;
    p.protocol = ehc_bringup::GraspProtocol::Poses;
    p.config_dir = EHC_CONFIG_DIR;
    p.sets = 1;
    p.per_set = 1;
    p.jobs = 1;
    const ehc_bringup::GraspExperiment exp(p, {"ehc"});
    const std::clock_t c0 = std::clock();
    const auto w0 = std::chrono::steady_clock::now();
    const ehc_bringup::GraspExperimentResult r = exp.run();
    const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    int ok = 0;
    for (const auto& t : r.trials) ok += t.success;
    std::printf("{\"bench\":\"grasp_pipeline_exp3_set\",\"grasps\":%zu,\"successes\":%d,\"sim_s\":%.2f,\"cpu_s\":%.2f,"
                "\"wall_s\":%.2f,\"cpu_real_time_factor\":%.2f,\"stages\":%s}\n",
                r.trials.size(), ok, r.sim_time_s, cpu, wall, r.sim_time_s / std::max(1e-9, cpu),
                ehc_bringup::pipelineStageCosts(r.counters, r.sim_time_s).c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_pipeline: %s\n", e.what());
    return 2;
  }
}
