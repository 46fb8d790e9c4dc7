// Guest-side helper for the e-stop-during-a-procedure test (guest/estop.sh):
//   gpio_sim_probe CHIP ESTOP_LINE POWER_LINE WAIT_S
// waits until the rig has switched the DUT's power on (the procedure runs),
// lets it run WAIT_S seconds more, opens the e-stop loop and measures how long
// the power line takes to go low. Exit 0 when within 50 ms.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "tests/kernel/gpio_sim.hpp"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s CHIP ESTOP_LINE POWER_LINE WAIT_S\n", argv[0]);
    return 2;
  }
  const rig::kernel_test::GpioSim sim(argv[1]);
  const int estop = std::atoi(argv[2]), power = std::atoi(argv[3]);
  const auto t0 = std::chrono::steady_clock::now();
  while (sim.value(power) != 1) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(300)) {
      std::fprintf(stderr, "gpio_sim_probe: the rig never switched the DUT power on\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::printf("gpio_sim_probe: DUT power on after %.1f s; e-stop in %s s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), argv[4]);
  std::fflush(stdout);
  std::this_thread::sleep_for(std::chrono::duration<double>(std::atof(argv[4])));
  const double latency = sim.trip_and_time_power_off(estop, power, 5.0);
  std::printf("gpio_sim_probe: [ measured ] e-stop edge -> DUT power line low: %.3f ms (limit 50 ms)\n", latency * 1e3);
  return latency < 0.050 ? 0 : 1;
}
