#include <gtest/gtest.h>

#include "occseg/error.hpp"
#include "occseg/params.hpp"

using namespace occseg;

TEST(Params, PaperValuesAreTheDefaults) {
  const Params p = Params::paper();
  EXPECT_EQ(p.smax, 64);
  EXPECT_EQ(p.smin, 8);
  EXPECT_DOUBLE_EQ(p.split_ratio, 1.2);
  EXPECT_EQ(p.contrast_bins, 8);
  EXPECT_DOUBLE_EQ(p.free_below, 0.498);
  EXPECT_DOUBLE_EQ(p.occupied_above, 0.502);
  EXPECT_EQ(p.lookahead, 3);
  EXPECT_EQ(p.refine_passes, 2);
  EXPECT_EQ(p.preset, Preset::paper);
  EXPECT_EQ(Params::defaults().preset, Preset::default_preset);
}

TEST(Params, SetByName) {
  Params p;
  set_param(p, "smin", "4");
  set_param(p, "split_ratio", "1.5");
  EXPECT_EQ(p.smin, 4);
  EXPECT_DOUBLE_EQ(p.split_ratio, 1.5);
  EXPECT_EQ(get_param(p, "smin"), "4");
  set_param(p, "preset", "paper");  // resets
  EXPECT_EQ(p.smin, 8);
  EXPECT_EQ(get_param(p, "preset"), "paper");
}

TEST(Params, BadNamesAndValuesAreErrorsNamingThem) {
  Params p;
  auto msg = [&](const char* n, const char* v) {
    try {
      set_param(p, n, v);
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::invalid_argument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(msg("smax2", "64").find("'smax2': no such parameter"), std::string::npos);
  EXPECT_NE(msg("smax", "abc").find("not a number"), std::string::npos);
  EXPECT_NE(msg("smax", "6.5").find("not an integer"), std::string::npos);
  EXPECT_NE(msg("contrast_bins", "1").find("outside [2, 64]"), std::string::npos);
  EXPECT_NE(msg("preset", "fast").find("not a preset"), std::string::npos);
  Params q;
  q.smax = 48;
  EXPECT_THROW(q.validate(), Error);
  q.smax = 8;
  q.smin = 16;
  EXPECT_THROW(q.validate(), Error);
}
