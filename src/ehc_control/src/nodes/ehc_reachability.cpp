// ehc_reachability: builds the arm reachability map offline (ROS-free tool).
//   rosrun ehc_control ehc_reachability --robot robot.yaml --samples N --out map.bin
//       [--seed S] [--resolution 0.05] [--direction-bins 32]
// Progress and ETA on stderr; a summary line on stdout. Errors: stderr, exit code 2.

#include "ehc_common/command_line.h"
#include "ehc_common/output_dir.h"
#include "ehc_control/reachability_map.h"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  const char* usage =
      "usage: ehc_reachability --robot <name|robot.yaml> --samples N --out <file> [--seed S]\n"
      "                        [--resolution m] [--direction-bins B (default 6)]\n";
  try {
    const ehc_common::CommandLine cli(
        argc, argv, {"robot", "samples", "out", "seed", "resolution", "direction-bins"}, {"help"});
    if (cli.has("help")) {
      std::cout << usage;
      return 0;
    }
    const std::string robot = ehc_control::resolveRobotFile(cli.text("robot"));  // a robot name or a robot.yaml
    const std::string out = cli.text("out");
    ehc_common::prepareOutputFile(out);  // before the (long) generation
    const long samples = cli.integer("samples", 0, 1, 1000000000L);
    if (!cli.has("samples")) cli.text("samples");  // "--samples is required"
    const auto seed = static_cast<unsigned>(cli.integer("seed", 1, 0, 4294967295L));
    ehc_control::ReachabilityMapParams params;
    params.resolution = cli.real("resolution", params.resolution);
    params.direction_bins = static_cast<int>(
        cli.integer("direction-bins", params.direction_bins, 1, 1000000));
    const ehc_control::WholeBodyModel model(ehc_control::loadRobotConfig(robot));
    const auto t0 = std::chrono::steady_clock::now();
    double last_print = -1.0;
    auto progress = [&](long done, long total) {
      const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (done != total && now - last_print < 2.0) return;  // throttle: every 2 s
      last_print = now;
      const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double eta = done > 0 ? el * static_cast<double>(total - done) / static_cast<double>(done) : 0.0;
      std::fprintf(stderr, "\r[ehc_reachability] %5.1f%%  %ld/%ld samples  elapsed %.0f s  ETA %.0f s ",
                   100.0 * static_cast<double>(done) / static_cast<double>(total), done, total, el, eta);
      if (done == total) std::fprintf(stderr, "\n");
    };
    const auto map = ehc_control::ReachabilityMap::generate(model, samples, seed, params, progress);
    map.save(out);
    std::cout << map.summary() << "\nwritten to " << out << std::endl;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "ehc_reachability: " << e.what() << "\n" << usage;
    return 2;
  }
}
