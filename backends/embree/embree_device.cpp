#include "backends/embree/embree_device.h"

#include <cstdio>
#include <stdexcept>

namespace twinray {

namespace {

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error code";
}

}  // namespace

EmbreeDevice::EmbreeDevice() {
  // Default configuration: TBB threads for builds, the best ISA of this CPU, no verbose output.
  device_ = rtcNewDevice(nullptr);
  if (device_ == nullptr) {
    // The callback cannot be registered before the device exists; the error is kept thread-locally.
    throw std::runtime_error(std::string("embree: cannot create a device: ") + error_name(rtcGetDeviceError(nullptr)));
  }
  rtcSetDeviceErrorFunction(device_, &EmbreeDevice::on_error, this);
  rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeDevice::on_memory, this);
}

EmbreeDevice::~EmbreeDevice() { rtcReleaseDevice(device_); }

std::size_t EmbreeDevice::allocated_bytes() const {
  const std::int64_t bytes = allocated_.load();
  return bytes > 0 ? static_cast<std::size_t>(bytes) : 0;
}

std::size_t EmbreeDevice::peak_allocated_bytes() const {
  return static_cast<std::size_t>(peak_.load());
}

void EmbreeDevice::throw_if_error(const char* what) {
  std::string message;
  {
    const std::lock_guard lock(error_mutex_);
    message.swap(first_error_);
  }
  if (!message.empty()) throw std::runtime_error(std::string("embree: ") + what + ": " + message);
}

void EmbreeDevice::on_error(void* self, RTCError code, const char* message) {
  auto& device = *static_cast<EmbreeDevice*>(self);
  std::string text = std::string(error_name(code)) + (message != nullptr ? std::string(": ") + message : "");
  if (device.report_immediately_.load()) {
    std::fprintf(stderr, "embree error: %s\n", text.c_str());
    return;
  }
  const std::lock_guard lock(device.error_mutex_);
  // The first error is the cause; later ones are usually its consequences.
  if (device.first_error_.empty()) device.first_error_ = std::move(text);
}

bool EmbreeDevice::on_memory(void* self, ssize_t bytes, bool /*post*/) {
  // `post` only tells whether the event is reported before or after the allocation happens; every
  // allocation and release is reported once either way, so the sum is right regardless.
  auto& device = *static_cast<EmbreeDevice*>(self);
  const std::int64_t now = device.allocated_.fetch_add(static_cast<std::int64_t>(bytes)) + bytes;
  std::int64_t peak = device.peak_.load();
  while (now > peak && !device.peak_.compare_exchange_weak(peak, now)) {
  }
  return true;  // never veto an allocation: twinray has no memory budget to enforce
}

}  // namespace twinray
