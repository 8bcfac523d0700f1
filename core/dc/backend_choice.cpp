// Which backend a job gets, and on which GPU: the "backend" and "gpus" settings.
#include <algorithm>
#include <atomic>
#include <mutex>
#include <string>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/dc/dc_backend.h"

namespace fenestra {
namespace {

std::mutex devices_mutex;
std::vector<int> chosen_devices;  // UseCudaDevices'; empty: every visible GPU

thread_local std::vector<int> thread_devices;  // ThreadCudaDevices'; empty: the process's
thread_local uint64_t thread_turn = 0;

// The GPUs NextCudaDevice takes in turn on this thread: its own, else the process's, else
// every visible one (none without a GPU).
std::vector<int> DevicesInUse() {
  if (!thread_devices.empty()) return thread_devices;
  {
    const std::lock_guard<std::mutex> lock(devices_mutex);
    if (!chosen_devices.empty()) return chosen_devices;
  }
  std::vector<int> visible;
  for (int d = 0; d < CudaDevices(); ++d) visible.push_back(d);
  return visible;
}

}  // namespace

void UseCudaDevices(std::vector<int> devices) {
  const std::lock_guard<std::mutex> lock(devices_mutex);
  chosen_devices = std::move(devices);
}

int NextCudaDevice() {
  static std::atomic<uint64_t> next{0};
  const uint64_t k = thread_devices.empty() ? next.fetch_add(1) : thread_turn++;
  const std::vector<int> devices = DevicesInUse();
  return devices.empty() ? 0 : devices[k % devices.size()];
}

int CudaDevicesInUse() { return static_cast<int>(DevicesInUse().size()); }

int LaneCudaDevice(int first, int lane) {
  const std::vector<int> devices = DevicesInUse();
  const auto at = std::find(devices.begin(), devices.end(), first);
  if (at == devices.end()) return first;
  const size_t index = static_cast<size_t>(at - devices.begin()) + static_cast<size_t>(lane);
  return devices[index % devices.size()];
}

absl::StatusOr<std::unique_ptr<DcBackend>> MakeLaneBackend(const std::string& name,
                                                           const DcBackend& first, int lane) {
  if (first.Gpu() < 0) return MakeBackend(name);
  return MakeCudaBackend(LaneCudaDevice(first.Gpu(), lane));
}

std::vector<int> WorkerCudaDevices(int worker, int workers) {
  const std::vector<int> all = DevicesInUse();
  std::vector<int> mine;
  if (all.empty() || workers < 1 || worker < 0) return mine;
  if (workers >= static_cast<int>(all.size())) return {all[worker % all.size()]};
  for (size_t d = worker; d < all.size(); d += workers) mine.push_back(all[d]);
  return mine;
}

ThreadCudaDevices::ThreadCudaDevices(std::vector<int> devices) : before_(thread_devices) {
  if (!devices.empty()) {
    thread_devices = std::move(devices);
    thread_turn = 0;
  }
}

ThreadCudaDevices::~ThreadCudaDevices() { thread_devices = before_; }

absl::StatusOr<std::vector<int>> ParseGpuList(const std::string& gpus, int visible) {
  std::vector<int> devices;
  if (gpus == "all") {
    for (int d = 0; d < visible; ++d) devices.push_back(d);
    return devices;
  }
  const std::string seen =
      visible > 0 ? absl::StrCat(visible, " visible: 0 to ", visible - 1) : "none visible";
  for (const absl::string_view part : absl::StrSplit(gpus, ',')) {
    int device = 0;
    if (!absl::SimpleAtoi(part, &device)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "gpus must be \"all\" or comma-separated device indices such as \"0,1\", got \"",
          absl::CHexEscape(gpus), "\""));
    }
    if (device < 0 || device >= visible) {
      return absl::InvalidArgumentError(
          absl::StrCat("gpus: there is no GPU ", device, " (", seen, ")"));
    }
    if (std::find(devices.begin(), devices.end(), device) != devices.end()) {
      return absl::InvalidArgumentError(absl::StrCat("gpus: GPU ", device, " is listed twice"));
    }
    devices.push_back(device);
  }
  return devices;
}

absl::StatusOr<std::unique_ptr<DcBackend>> MakeBackend(const std::string& name) {
  if (name == "cpu") return MakeEmbreeBackend();
  if (name == "cuda") return MakeCudaBackend(NextCudaDevice());
  if (name == "auto") {
    if (CudaDevices() > 0) return MakeCudaBackend(NextCudaDevice());
    return MakeEmbreeBackend();
  }
  return absl::InvalidArgumentError("backend must be cpu, cuda or auto, got '" + name + "'");
}

}  // namespace fenestra
