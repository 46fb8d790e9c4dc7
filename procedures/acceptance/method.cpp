#include "procedures/acceptance/method.hpp"

namespace rig::acceptance {

AllanSettings allan_settings(const Profile& p) { return {p.rate_hz, p.taus, p.confidence, p.r_min_record_s}; }

AllanChannel allan_channel_terms(const std::vector<double>& record, const AllanSettings& s,
                                 const std::function<void()>& poll) {
  analysis::DevOptions opt;
  opt.poll = poll;
  opt.type = analysis::Deviation::OADEV;
  opt.data = analysis::DataKind::Frequency;
  opt.rate_hz = s.rate_hz;
  opt.taus = analysis::parse_tau_grid(s.taus);
  opt.confidence = s.confidence;
  AllanChannel c;
  c.oadev = analysis::deviation(record, opt);
  const double T = static_cast<double>(record.size()) / s.rate_hz;
  if (poll) poll();
  c.terms = analysis::noise_terms(c.oadev, T, s.r_min_record_s, analysis::least_squares_drift(record, s.rate_hz),
                                 s.confidence);
  return c;
}

}  // namespace rig::acceptance
