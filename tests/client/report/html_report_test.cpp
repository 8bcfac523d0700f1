// The report page of a quick job, rendered by headless Chromium: it loads without console
// errors or requests beyond itself, every figure is there with its content, no text
// overlaps or leaves its figure, and it prints. A screenshot is kept as a test artifact.
#include "client/report/html_report.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/geometry/blind.h"
#include "core/geometry/scene.h"
#include "tests/client/report/direct_sun_result.h"
#include "tests/headless_chromium.h"
#include "tests/quick_job.h"

namespace fenestra {

// Results with a Pareto front, and with glare at view points (report_data_test.cpp).
v1::JobResult WithParetoFront(v1::JobResult r, bool three);
v1::JobResult WithGlareAtViews(v1::JobResult r);

namespace {

namespace fs = std::filesystem;
using google::protobuf::Value;
using ::testing::IsEmpty;

// Per figure: its size and how many of its parts were drawn; the texts that overlap
// another text of their figure or leave it.
constexpr char kInspectFigures[] = R"js((() => {
  const out = {figures: {}, overlaps: [], outside: []};
  for (const svg of document.querySelectorAll('svg.figure')) {
    const box = svg.getBoundingClientRect();
    const count = (selector) => svg.querySelectorAll(selector).length;
    out.figures[svg.id] = {width: box.width, height: box.height,
                           points: count('.evaluations .point'), sensors: count('.sensor'),
                           labels: count('.sensor-value'), cells: count('.map-cell'),
                           occupancy: count('.occupied-hours .occupancy'), slats: count('.slat'),
                           marked: count('.marked-sensor')};
    const texts = [...svg.querySelectorAll('text')].map(t => [t.textContent, t.getBoundingClientRect()]);
    for (const [text, r] of texts) {
      if (r.left < box.left - 1 || r.right > box.right + 1 || r.top < box.top - 1 ||
          r.bottom > box.bottom + 1) out.outside.push(svg.id + ': ' + text);
    }
    for (let i = 0; i < texts.length; ++i) {
      for (let j = i + 1; j < texts.length; ++j) {
        const a = texts[i][1], b = texts[j][1];
        const w = Math.min(a.right, b.right) - Math.max(a.left, b.left);
        const h = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
        if (w > 1 && h > 1) out.overlaps.push(svg.id + ': ' + texts[i][0] + ' / ' + texts[j][0]);
      }
    }
  }
  return out;
})())js";

const Value& Get(const Value& v, const std::string& field) {
  static const Value* const kNull = new Value();
  const auto& fields = v.struct_value().fields();
  const auto it = fields.find(field);
  return it == fields.end() ? *kNull : it->second;
}

std::vector<std::string> Strings(const Value& list) {
  std::vector<std::string> out;
  for (const Value& v : list.list_value().values()) out.push_back(v.string_value());
  return out;
}

// The figures of `result`'s page: nine, and those of the direct sun where it holds them.
int FigureCount(const v1::JobResult& result) {
  const v1::HourlyIlluminance& h = result.best_hourly();
  return 9 + (result.best_metrics().sensor_sunlit_hours_size() > 0) +
         (h.direct_sun_lux_size() > 0) +
         (std::find(h.blind_in_place().begin(), h.blind_in_place().end(), false) !=
          h.blind_in_place().end());
}

// The summary's rows of metrics: seven, ASE and the blind's hours where the result holds them.
int MetricRows(const v1::JobResult& result) {
  const v1::Metrics& m = result.best_metrics();
  const bool operated =
      result.job().scene().blind().operation() == v1::VenetianBlind::AUTOMATED_SUN;
  return 7 + m.has_ase() + (operated && m.has_blind_in_place());
}

class HtmlReportTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fenestra_html_report_" +
            std::string(testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const v1::JobResult& result = QuickJobResult();
    ASSERT_TRUE(result.has_best_hourly());
    page_ = (dir_ / "report.html").string();
    ASSERT_TRUE(WriteReport(result, {"quick.json", ""}, page_).ok());
    absl::StatusOr<std::unique_ptr<HeadlessChromium>> browser =
        HeadlessChromium::Start(CHROMIUM_EXECUTABLE, (dir_ / "profile").string());
    ASSERT_TRUE(browser.ok()) << browser.status();
    browser_ = *std::move(browser);
    const absl::Status loaded = browser_->Load("file://" + page_, 1200, 900);
    ASSERT_TRUE(loaded.ok()) << loaded;
  }
  void TearDown() override {
    browser_.reset();
    if (!HasFailure()) fs::remove_all(dir_);
  }

  Value Inspect() {
    absl::StatusOr<Value> value = browser_->Evaluate(kInspectFigures);
    EXPECT_TRUE(value.ok()) << value.status();
    return value.ok() ? *value : Value();
  }

  // The page of `result` (as `name`.html) loaded, checked for console problems, text that
  // overlaps or leaves its figure; its figures' measurements.
  Value LoadAndInspect(const v1::JobResult& result, const std::string& name) {
    const std::string page = (dir_ / (name + ".html")).string();
    EXPECT_TRUE(WriteReport(result, {name + ".json", ""}, page).ok());
    const absl::Status loaded = browser_->Load("file://" + page, 1200, 900);
    EXPECT_TRUE(loaded.ok()) << loaded;
    EXPECT_THAT(browser_->problems(), IsEmpty());
    const Value inspected = Inspect();
    EXPECT_THAT(Strings(Get(inspected, "overlaps")), IsEmpty());
    EXPECT_THAT(Strings(Get(inspected, "outside")), IsEmpty());
    return Get(inspected, "figures");
  }

  fs::path dir_;
  std::string page_;
  std::unique_ptr<HeadlessChromium> browser_;
};

TEST_F(HtmlReportTest, LoadsWithoutErrorsOrRequestsAndDrawsEveryFigure) {
  EXPECT_THAT(browser_->problems(), IsEmpty());
  EXPECT_EQ(browser_->requests(), std::vector<std::string>{"file://" + page_});
  absl::StatusOr<Value> scripts =
      browser_->Evaluate("document.querySelectorAll('script, [src], link, iframe').length");
  ASSERT_TRUE(scripts.ok()) << scripts.status();
  EXPECT_EQ(scripts->number_value(), 0);

  const v1::JobResult& result = QuickJobResult();
  const Value figures = Get(Inspect(), "figures");
  for (const char* id : {"plot-value-vs-evaluation", "plot-value-vs-time", "plot-error-vs-time",
                         "plot-design-alpha", "plot-floor-udi", "plot-floor-da",
                         "plot-temporal-map", "plot-blind-section", "plot-blind-detail"}) {
    const Value& figure = Get(figures, id);
    ASSERT_TRUE(figure.has_struct_value()) << id << " is missing";
    EXPECT_GT(Get(figure, "width").number_value(), 200) << id;
    EXPECT_GT(Get(figure, "height").number_value(), 150) << id;
  }
  EXPECT_EQ(Get(Get(figures, "plot-value-vs-evaluation"), "points").number_value(),
            result.history_size());
  EXPECT_EQ(Get(Get(figures, "plot-design-alpha"), "points").number_value(), result.history_size());
  EXPECT_EQ(Get(Get(figures, "plot-floor-udi"), "sensors").number_value(), 9);
  EXPECT_EQ(Get(Get(figures, "plot-floor-udi"), "labels").number_value(), 9);
  EXPECT_GT(Get(Get(figures, "plot-temporal-map"), "cells").number_value(), 24);
  EXPECT_EQ(Get(Get(figures, "plot-temporal-map"), "occupancy").number_value(), 1);
  // As many slats as the generator makes at the best design
  absl::StatusOr<Scene> scene = BuildScene(result.job().scene(), "result");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const std::map<std::string, double> best(result.best_design().begin(),
                                           result.best_design().end());
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(*scene, best);
  ASSERT_TRUE(design.ok()) << design.status();
  EXPECT_EQ(Get(Get(figures, "plot-blind-section"), "slats").number_value(),
            LayoutBlind(scene->window(), *scene->blind(), *design).slat_count);

  // The tables, the job's final check and its recorded error against time
  absl::StatusOr<Value> text = browser_->Evaluate(
      "[document.querySelectorAll('#sensor-table tbody tr').length, "
      "document.querySelectorAll('#best-metrics-table tbody tr').length, "
      "document.querySelectorAll('#final-check-table tbody tr').length, "
      "document.querySelectorAll('polyline.recorded-line').length]");
  ASSERT_TRUE(text.ok()) << text.status();
  const auto& values = text->list_value().values();
  EXPECT_EQ(values[0].number_value(), 9);
  EXPECT_EQ(values[1].number_value(), MetricRows(result));
  EXPECT_EQ(values[2].number_value(), 6);
  EXPECT_EQ(values[3].number_value(), 1);
}

TEST_F(HtmlReportTest, NoTextOverlapsOrLeavesItsFigure) {
  const Value inspected = Inspect();
  EXPECT_THAT(Strings(Get(inspected, "overlaps")), IsEmpty());
  EXPECT_THAT(Strings(Get(inspected, "outside")), IsEmpty());

  // The screenshot, kept for people to look at
  absl::StatusOr<std::string> png = browser_->Screenshot();
  ASSERT_TRUE(png.ok()) << png.status();
  ASSERT_GT(png->size(), 8u);
  EXPECT_EQ(png->substr(1, 3), "PNG");
  const fs::path artifact =
      fs::path(FENESTRA_BINARY_DIR) / "test_artifacts" / "report_screenshot.png";
  fs::create_directories(artifact.parent_path());
  std::ofstream(artifact, std::ios::binary) << *png;
  RecordProperty("screenshot", artifact.string());
}

TEST_F(HtmlReportTest, PrintsWithEveryFigure) {
  ASSERT_TRUE(browser_->EmulateMedia("print").ok());
  absl::StatusOr<Value> visible = browser_->Evaluate(
      "[...document.querySelectorAll('svg.figure')].filter(s => s.getBoundingClientRect().width "
      "> 100).length");
  ASSERT_TRUE(visible.ok()) << visible.status();
  EXPECT_EQ(visible->number_value(), FigureCount(QuickJobResult()));
  absl::StatusOr<Value> background =
      browser_->Evaluate("getComputedStyle(document.body).backgroundColor");
  ASSERT_TRUE(background.ok()) << background.status();
  EXPECT_EQ(background->string_value(), "rgb(255, 255, 255)");
  absl::StatusOr<std::string> pdf = browser_->PrintToPdf();
  ASSERT_TRUE(pdf.ok()) << pdf.status();
  EXPECT_EQ(pdf->substr(0, 5), "%PDF-");
  EXPECT_GT(pdf->size(), 20000u);
  EXPECT_THAT(browser_->problems(), IsEmpty());
}

// The direct sun's figures: the sensors' sunlit hours and the maps of the direct sun and of
// the blind in place, with no text overlapping or leaving them
TEST_F(HtmlReportTest, DrawsTheDirectSunAndTheOperatedBlind) {
  const v1::JobResult sunny = WithDirectSun(QuickJobResult());
  const Value figures = LoadAndInspect(sunny, "sunny");
  EXPECT_EQ(static_cast<int>(figures.struct_value().fields().size()), FigureCount(sunny));
  for (const char* id : {"plot-floor-sunlit", "plot-direct-sun-map", "plot-blind-map"}) {
    const Value& figure = Get(figures, id);
    ASSERT_TRUE(figure.has_struct_value()) << id << " is missing";
    EXPECT_GT(Get(figure, "width").number_value(), 200) << id;
    EXPECT_GT(Get(figure, "height").number_value(), 150) << id;
  }
  EXPECT_EQ(Get(Get(figures, "plot-floor-sunlit"), "sensors").number_value(), 9);
  EXPECT_EQ(Get(Get(figures, "plot-floor-sunlit"), "labels").number_value(), 9);
  EXPECT_EQ(Get(Get(figures, "plot-floor-sunlit"), "marked").number_value(), 2);
  EXPECT_GT(Get(Get(figures, "plot-direct-sun-map"), "cells").number_value(), 24);
  EXPECT_EQ(Get(Get(figures, "plot-blind-map"), "occupancy").number_value(), 1);
  absl::StatusOr<Value> rows = browser_->Evaluate(
      "[document.querySelectorAll('#constraints-table tbody tr').length, "
      "document.querySelectorAll('#best-metrics-table tbody tr').length, "
      "document.getElementById('leed').textContent]");
  ASSERT_TRUE(rows.ok()) << rows.status();
  const auto& values = rows->list_value().values();
  EXPECT_EQ(values[0].number_value(), 1);
  EXPECT_EQ(values[1].number_value(), 9);
  EXPECT_EQ(values[2].string_value(), "LEED v4.1 daylight option 1: 1 point; ASE at most 10%: no");
}

// A Pareto search's page with glare at view points: the front with its members, letters and
// error bars, the hypervolume, the blinds of A, B and C, the DGP maps and the views on the
// plans, with no text overlapping or leaving its figure
TEST_F(HtmlReportTest, DrawsTheParetoFrontTheGlareMapsAndTheViews) {
  const v1::JobResult result = WithGlareAtViews(WithParetoFront(QuickJobResult(), false));
  const Value figures = LoadAndInspect(result, "pareto");
  for (const char* id :
       {"plot-pareto-front", "plot-hypervolume", "plot-pareto-blind-a", "plot-pareto-blind-b",
        "plot-pareto-blind-c", "plot-glare-map-0", "plot-glare-map-1"}) {
    const Value& figure = Get(figures, id);
    ASSERT_TRUE(figure.has_struct_value()) << id << " is missing";
    EXPECT_GT(Get(figure, "width").number_value(), 200) << id;
    EXPECT_GT(Get(figure, "height").number_value(), 150) << id;
  }
  EXPECT_EQ(Get(Get(figures, "plot-pareto-front"), "points").number_value(), 9);
  EXPECT_GT(Get(Get(figures, "plot-pareto-blind-c"), "slats").number_value(), 1);
  EXPECT_GT(Get(Get(figures, "plot-glare-map-0"), "cells").number_value(), 24);
  EXPECT_EQ(Get(Get(figures, "plot-glare-map-0"), "occupancy").number_value(), 1);
  absl::StatusOr<Value> counts = browser_->Evaluate(
      "[document.querySelectorAll('#plot-pareto-front .front .front-member').length, "
      "[...document.querySelectorAll('#plot-pareto-front .pareto-label')].map(t => "
      "t.textContent).join(''), "
      "document.querySelectorAll('#pareto-front-table tbody tr').length, "
      "document.querySelectorAll('#plot-floor-udi .views .view-point').length, "
      "document.querySelectorAll('#glare-table tbody tr').length]");
  ASSERT_TRUE(counts.ok()) << counts.status();
  const auto& values = counts->list_value().values();
  EXPECT_EQ(values[0].number_value(), 5);
  EXPECT_EQ(values[1].string_value(), "ABC");
  EXPECT_EQ(values[2].number_value(), 5);
  EXPECT_EQ(values[3].number_value(), 3);
  EXPECT_EQ(values[4].number_value(), 3);
}

// The inspection itself finds overlapping and clipped texts
TEST_F(HtmlReportTest, TheInspectionFindsOverlapsAndClippedTexts) {
  const std::string page = (dir_ / "bad.html").string();
  std::ofstream(page)
      << "<!DOCTYPE html><html><body><svg class=\"figure\" id=\"bad\" width=\"200\" "
         "height=\"60\"><text x=\"10\" y=\"20\">hello</text><text x=\"14\" "
         "y=\"24\">world</text><text x=\"180\" y=\"50\">clipped</text>"
         "</svg></body></html>";
  ASSERT_TRUE(browser_->Load("file://" + page, 800, 600).ok());
  const Value inspected = Inspect();
  EXPECT_EQ(Strings(Get(inspected, "overlaps")), std::vector<std::string>{"bad: hello / world"});
  EXPECT_EQ(Strings(Get(inspected, "outside")), std::vector<std::string>{"bad: clipped"});
}

}  // namespace
}  // namespace fenestra
