#include "CancelOnSignal.hpp"

#include <csignal>

namespace regolith::tools {

namespace {

// Set by SIGINT/SIGTERM during a write: the writer then stops and removes its temporary file.
std::atomic<bool> gCancel{false};  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)
static_assert(std::atomic<bool>::is_always_lock_free);

extern "C" void onSignal(int /*signal*/) { gCancel.store(true); }

}  // namespace

CancelOnSignal::CancelOnSignal() {
  gCancel.store(false);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

CancelOnSignal::~CancelOnSignal() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

const std::atomic<bool>* CancelOnSignal::flag() noexcept { return &gCancel; }

}  // namespace regolith::tools
