// The in-process emulated DUT reached through the real protocol: an in-process
// CAN bus, the firmware emulator on one port and the rig's CanDutLink on
// another, owned together. The world advances it with step(dt) (lockstep with
// a SimClock); the rig uses it as any rig::DutLink.
#pragma once
#include <memory>

#include "firmware_link/can_dut_link.hpp"
#include "firmware_link/inprocess_bus.hpp"
#include "plant/firmware/firmware_emulator.hpp"

namespace rig::link {

struct InProcessDutOptions {
  plant::FirmwareOptions firmware;
  LinkOptions link;
};

class InProcessDutLink final : public DutLink {
 public:
  // `source` and `clock` must outlive this object. `clock` is the simulated time the
  // bus owns (its advance normally calls step()); the rig's client reads time off it.
  InProcessDutLink(plant::DutSource& source, SimClock& clock, InProcessDutOptions opts = {});
  ~InProcessDutLink() override;

  // Lockstep: advance the emulated firmware by dt seconds of simulated time.
  void step(double dt_s) { firmware_->step(dt_s); }
  plant::FirmwareEmulator& firmware() { return *firmware_; }
  CanDutLink& client() { return *client_; }
  InProcessBus& bus() { return *bus_; }

  DutInfo info(const CancelToken& c) override { return client_->info(c); }
  void start_stream(const CancelToken& c) override { client_->start_stream(c); }
  void stop_stream() noexcept override { client_->stop_stream(); }
  std::size_t read(std::span<Sample> out, const CancelToken& c) override { return client_->read(out, c); }
  void set_filter(const FilterConfig& f, const CancelToken& c) override { client_->set_filter(f, c); }
  FilterConfig get_filter(const CancelToken& c) override { return client_->get_filter(c); }
  LinkStats stats() const override { return client_->stats(); }
  void reset_stats() override { client_->reset_stats(); }
  std::string describe() const override;
  LoopTestResponse loop_test(const LoopTestRequest& r, const CancelToken& c) override { return client_->loop_test(r, c); }
  DutCommandChannel command_channel() const override { return client_->command_channel(); }

 private:
  std::shared_ptr<InProcessBus> bus_;
  std::unique_ptr<CanTransport> dut_port_;
  std::unique_ptr<plant::FirmwareEmulator> firmware_;
  std::unique_ptr<CanDutLink> client_;
};

// The factory the world calls. Keep the returned pointer's step() for the
// SimClock's advance; the object converts to std::unique_ptr<rig::DutLink>.
std::unique_ptr<InProcessDutLink> make_inprocess_dut(plant::DutSource& source, SimClock& clock,
                                                     InProcessDutOptions opts = {});

}  // namespace rig::link
