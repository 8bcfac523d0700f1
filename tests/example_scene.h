#pragma once

// The example scenes (examples/<name>/scene.json), for tests.
#include <gtest/gtest.h>

#include <string>

#include "core/geometry/scene.h"

namespace fenestra {

inline Scene LoadExample(const std::string& name) {
  absl::StatusOr<Scene> scene = LoadScene(FENESTRA_SOURCE_DIR "/examples/" + name + "/scene.json");
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene.ok() ? *std::move(scene) : Scene{};
}

}  // namespace fenestra
