// The entries of an MMT summary.json, for the single-process run, the
// stations of two processes and their report alike. Internal to the
// session layer.
#pragma once

#include <nlohmann/json.hpp>

#include "terracut/net/emulator.hpp"
#include "terracut/net/messages.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::session {

/// Rejected datagrams by reason name ("truncated": n, ...).
nlohmann::ordered_json rejected_json(const net::RejectCounts& c);
/// A direction's emulated conditions (the "link" entry's keys).
nlohmann::ordered_json link_json(const net::LinkConditions& c);
/// Everything of a run's summary.json from "duration_s" on: force and
/// terrain errors, tracking, traffic, updates, the estimate, passivity,
/// rejections and timing.
nlohmann::ordered_json summary_json(const MmtSummary& s);

}  // namespace terracut::session
