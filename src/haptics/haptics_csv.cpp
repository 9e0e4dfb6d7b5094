// haptics.csv. See haptics_csv.hpp.
#include "terracut/haptics/haptics_csv.hpp"

#include "terracut/io/recording.hpp"

namespace terracut::haptics {

void write_haptics_csv(const std::filesystem::path& path, const std::vector<LoopRecord>& records) {
  io::CsvFile csv(path, kHapticsCsvColumns);
  for (const LoopRecord& r : records) {
    const auto bit = [&](std::uint32_t b) { return (r.flags & b) ? 1 : 0; };
    csv.row({r.t_s, r.tick, r.device_position_m.x, r.device_position_m.y, r.device_position_m.z,
             r.tool.position_m.x, r.tool.position_m.y, r.tool.position_m.z, r.tool.orientation.w,
             r.tool.orientation.x, r.tool.orientation.y, r.tool.orientation.z, r.contact_length_m,
             r.cut_depth_m, r.removed_volume_m3, r.velocity_m_per_s.x, r.velocity_m_per_s.y,
             r.velocity_m_per_s.z, r.force_world_n.x, r.force_world_n.y, r.force_world_n.z,
             r.body_force_world_n.x, r.body_force_world_n.y, r.body_force_world_n.z,
             r.force_device_n.x, r.force_device_n.y, r.force_device_n.z, bit(kFlagClamped),
             bit(kFlagRateLimited), bit(kFlagWatchdog), bit(kFlagRamping), bit(kFlagNonfinite),
             bit(kFlagBadSample), bit(kFlagSilent), bit(kFlagMissedDeadline), r.period_s,
             r.compute_s, r.penetration_force_n, r.twist_torque_n_m, r.yaw_rate_rad_per_s,
             r.physical_force_world_n.x, r.physical_force_world_n.y, r.physical_force_world_n.z});
  }
  csv.close();
}

}  // namespace terracut::haptics
