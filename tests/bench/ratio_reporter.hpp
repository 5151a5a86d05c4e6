// A console reporter that also keeps each benchmark's time per item (from items_per_second), so a
// benchmark program can print its fast path beside the naive reference measured in the same run.
#pragma once

#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <vector>

namespace omniloc::bench {

class RatioReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, double> ns_per_item;
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration) continue;
      const auto items = r.counters.find("items_per_second");
      if (items != r.counters.end() && items->second.value > 0)
        ns_per_item[r.benchmark_name()] = 1e9 / items->second.value;
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

}  // namespace omniloc::bench
