// A table that is never moved: the seam's fake for tests of phases that do not turn the DUT
// (the loop phase). Header-only, on rig/core alone, so the procedure-without-plant test can use it.
#pragma once
#include <optional>
#include <string>
#include <utility>

#include "rig/core/table.hpp"

namespace rig::test {

class IdleTable final : public RotaryTable {
 public:
  TableStatus status() override { return {}; }
  void home(const CancelToken&) override {}
  void move_to(double, const CancelToken&) override {}
  void stop() noexcept override {}
  void quick_stop() noexcept override {}
  std::string describe() const override { return "idle table"; }
  std::optional<std::pair<double, double>> travel_deg(const CancelToken&) override { return travel; }
  std::optional<std::pair<double, double>> travel;  // what the drive would report (none: cannot tell)
};

}  // namespace rig::test
