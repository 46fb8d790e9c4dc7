#include "plant/firmware/inprocess_dut.hpp"

namespace rig::link {

InProcessDutLink::InProcessDutLink(plant::DutSource& source, SimClock& clock, InProcessDutOptions opts) {
  InProcessBus::Options bo;
  bo.name = "dut-bus";
  bo.lockstep = &clock;  // the bus owns simulated time: the client's receive steps the world
  bus_ = InProcessBus::create(std::move(bo));
  dut_port_ = bus_->open("dut");
  firmware_ = std::make_unique<plant::FirmwareEmulator>(source, *dut_port_, opts.firmware);
  client_ = std::make_unique<CanDutLink>(bus_->open("rig"), clock, opts.link);
}

InProcessDutLink::~InProcessDutLink() {
  client_.reset();  // its stop frame reaches the firmware's queue, harmlessly
  firmware_.reset();
}

std::string InProcessDutLink::describe() const { return "emulated DUT firmware, " + client_->describe(); }

std::unique_ptr<InProcessDutLink> make_inprocess_dut(plant::DutSource& source, SimClock& clock,
                                                     InProcessDutOptions opts) {
  return std::make_unique<InProcessDutLink>(source, clock, std::move(opts));
}

}  // namespace rig::link
