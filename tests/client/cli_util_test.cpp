// What the client's commands share: state names, the JSON printer, file reading.
#include "client/cli_util.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(CliUtilTest, StateNames) {
  EXPECT_EQ(StateName(v1::SITE_STATE_COMPUTING), "computing");
  EXPECT_EQ(StateName(v1::SITE_STATE_READY), "ready");
  EXPECT_EQ(StateName(v1::SITE_STATE_FAILED), "failed");
  EXPECT_EQ(StateName(v1::JOB_STATE_QUEUED), "queued");
  EXPECT_EQ(StateName(v1::JOB_STATE_RUNNING), "running");
  EXPECT_EQ(StateName(v1::JOB_STATE_SUCCEEDED), "succeeded");
  EXPECT_EQ(StateName(v1::JOB_STATE_CANCELLED), "cancelled");
  EXPECT_EQ(StateName(v1::JOB_STATE_INTERRUPTED), "interrupted");
  // A state a newer fenestrad may send
  EXPECT_EQ(StateName(static_cast<v1::JobState>(42)), "unknown (42)");
  EXPECT_EQ(StateName(static_cast<v1::SiteState>(9)), "unknown (9)");
}

TEST(CliUtilTest, FinalStates) {
  for (const v1::JobState state : {v1::JOB_STATE_SUCCEEDED, v1::JOB_STATE_FAILED,
                                   v1::JOB_STATE_CANCELLED, v1::JOB_STATE_INTERRUPTED}) {
    EXPECT_TRUE(IsFinalState(state)) << StateName(state);
  }
  for (const v1::JobState state :
       {v1::JOB_STATE_UNSPECIFIED, v1::JOB_STATE_QUEUED, v1::JOB_STATE_RUNNING}) {
    EXPECT_FALSE(IsFinalState(state)) << StateName(state);
  }
}

TEST(CliUtilTest, JsonLayouts) {
  v1::JobInfo job;
  job.set_id("job-1");
  job.set_state(v1::JOB_STATE_RUNNING);
  job.set_queue_position(0);
  EXPECT_EQ(ToJson(job, JsonLayout::kLine), R"({"id":"job-1","state":"JOB_STATE_RUNNING"})");
  EXPECT_EQ(ToJson(job, JsonLayout::kIndented),
            "{\n \"id\": \"job-1\",\n \"state\": \"JOB_STATE_RUNNING\"\n}");
  // Result files: proto field names and every field
  const std::string file = ToJson(job, JsonLayout::kResultFile);
  EXPECT_THAT(file, HasSubstr("\"queue_position\": 0"));
  EXPECT_THAT(file, HasSubstr("\"cancel_requested\": false"));
}

TEST(CliUtilTest, ReadFileBytesSaysWhy) {
  const std::string dir = testing::TempDir();
  EXPECT_EQ(ReadFileBytes(dir + "/no_such_file").status().message(),
            dir + "/no_such_file: cannot open (No such file or directory)");
  EXPECT_EQ(ReadFileBytes(dir).status().message(), dir + ": cannot open (a directory)");
}

}  // namespace
}  // namespace fenestra
