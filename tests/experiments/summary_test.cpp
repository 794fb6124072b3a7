#include "experiments/summary.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

// By hand: values 1..5 have mean 3, sample sd sqrt(2.5) = 1.58114, and the 95% interval
// half-width is t_{0.975, 4} sd / sqrt(5) = 2.776445 * 1.58114 / 2.23607 = 1.96324.
TEST(Summary, MeanAndConfidenceIntervalByHand) {
  const std::vector<SummaryRow> rows =
      summarise({"a", "a", "a", "a", "a", "b"}, {0, 0, 0, 0, 0, 3}, {1, 2, 3, 4, 5, 7});
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].method, "a");
  EXPECT_EQ(rows[0].n, 5);
  EXPECT_DOUBLE_EQ(rows[0].mean, 3.0);
  EXPECT_NEAR(rows[0].sd, 1.5811388, 1e-7);
  EXPECT_NEAR(rows[0].ci95, 1.9632432, 1e-6);
  EXPECT_EQ(rows[1].n, 1);
  EXPECT_EQ(rows[1].ci95, 0.0);  // one run: no interval
}

TEST(Summary, OrderAndTables) {
  const std::vector<SummaryRow> rows = summarise({"z", "a", "z", "a"}, {5, 5, 1, 1}, {1, 2, 3, 4});
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].method, "z");  // methods in order of first appearance
  EXPECT_EQ(rows[0].x, 1);         // then x ascending
  const std::string csv = summary_csv(rows, "confounders");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "method,confounders,runs,mean,sd,ci95");
  const std::string md = summary_markdown(rows, "|E|", "ILE");
  EXPECT_NE(md.find("| |E| | z | a |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 1 | 3.000 ± 0.000 | 4.000 ± 0.000 |"), std::string::npos) << md;
}

}  // namespace
}  // namespace hbirl
