#pragma once
// A Google Benchmark reporter that prints the usual table and keeps each
// benchmark's median of its repetitions, for the JSON line a bench program
// prints at the end (docs/ tables are made from it).
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

namespace pex::bench {

class MedianCollector : public benchmark::ConsoleReporter {
 public:
  // CPU time, in the benchmark's unit, by "function/args": on a shared
  // machine wall time mostly measures the other processes.
  std::map<std::string, double> median_ms;
  std::map<std::string, double> median_counter;  // "function/args/counter"

  // Google Benchmark's flags from the command line, then every benchmark
  // selected, reported here.
  void run(int* argc, char** argv) {
    benchmark::Initialize(argc, argv);
    benchmark::RunSpecifiedBenchmarks(this);
  }

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& run : runs)
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name == "median") {
        const std::string name = run.run_name.function_name + "/" + run.run_name.args;
        median_ms[name] = run.GetAdjustedCPUTime();
        for (const auto& [counter, value] : run.counters) median_counter[name + "/" + counter] = value.value;
      }
    ConsoleReporter::ReportRuns(runs);
  }

  // The median of a benchmark, -1 if it did not run (filtered out).
  double median(const std::string& name) const {
    const auto it = median_ms.find(name);
    return it == median_ms.end() ? -1.0 : it->second;
  }
};

}  // namespace pex::bench
