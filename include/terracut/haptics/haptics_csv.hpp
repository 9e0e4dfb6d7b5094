// haptics.csv: one row per tick of a haptic loop (a LoopRecord), the columns
// documented in docs/haptics.md; written with io::CsvFile, terracut's one
// CSV writer.
#pragma once

#include <filesystem>
#include <vector>

#include "terracut/haptics/loop.hpp"

namespace terracut::haptics {

/// The columns of haptics.csv, in order.
inline constexpr const char* kHapticsCsvColumns =
    "t,tick,dev_x,dev_y,dev_z,tool_x,tool_y,tool_z,qw,qx,qy,qz,contact_length,cut_depth,"
    "removed_volume,vel_x,vel_y,vel_z,fw_x,fw_y,fw_z,fb_x,fb_y,fb_z,fd_x,fd_y,fd_z,clamped,"
    "rate_limited,watchdog,ramping,nonfinite,bad_sample,silent,missed_deadline,period,compute,"
    "f_penetration,twist_torque,yaw_rate,fp_x,fp_y,fp_z";

/// Writes records as haptics.csv at path (kHapticsCsvColumns, then one row
/// per record): numbers with %.9g, flags as 0 / 1. Throws InputError naming
/// the file when it cannot be written.
void write_haptics_csv(const std::filesystem::path& path, const std::vector<LoopRecord>& records);

}  // namespace terracut::haptics
