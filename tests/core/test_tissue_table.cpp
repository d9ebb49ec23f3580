#include "core/error.hpp"
#include "core/tissue_table.hpp"

#include <gtest/gtest.h>

using namespace phantasm;

TEST(TissueTable, BuiltinTableHoldsTwentySevenTissuesAtTwoFieldStrengths) {
  const TissueTable& table = TissueTable::builtin();
  EXPECT_EQ(table.tissue_names().size(), 27u);
  EXPECT_EQ(table.records().size(), 54u);
  for (const auto& name : table.tissue_names()) {
    EXPECT_EQ(table.field_strengths(name), (std::vector<double>{1.5, 3.0})) << name;
  }
}

TEST(TissueTable, BuiltinValuesKeepTheirSources) {
  const TissueRecord* wm = TissueTable::builtin().find("white_matter", 3.0);
  ASSERT_NE(wm, nullptr);
  EXPECT_DOUBLE_EQ(*wm->T1_ms, 810.0);
  EXPECT_DOUBLE_EQ(*wm->T2_ms, 80.0);
  EXPECT_DOUBLE_EQ(*wm->T2star_ms, 53.2);
  EXPECT_DOUBLE_EQ(*wm->PD, 0.7);
  EXPECT_NE(wm->T1_source.find("Marques"), std::string::npos);
  EXPECT_NE(wm->T2_source.find("Wansapura"), std::string::npos);
  // A quoted field with commas inside stays one field.
  const TissueRecord* liver = TissueTable::builtin().find("liver", 1.5);
  ASSERT_NE(liver, nullptr);
  EXPECT_EQ(liver->T1_source, "de Bazelaire et al. 2004 Radiology 230:652 (in vivo, 1.5/3 T)");
}

// Every value of the shipped table names where it comes from.
TEST(TissueTable, EveryBuiltinValueNamesItsSource) {
  for (const TissueRecord& r : TissueTable::builtin().records()) {
    const std::string what = r.tissue + " at " + std::to_string(r.field_T) + " T";
    EXPECT_TRUE(!r.T1_ms || !r.T1_source.empty()) << what << ": T1";
    EXPECT_TRUE(!r.T2_ms || !r.T2_source.empty()) << what << ": T2";
    EXPECT_TRUE(!r.T2star_ms || !r.T2star_source.empty()) << what << ": T2*";
    EXPECT_TRUE(!r.PD || !r.PD_source.empty()) << what << ": PD";
  }
}

TEST(TissueTable, MissingValuesStayEmpty) {
  const TissueTable& table = TissueTable::builtin();
  EXPECT_FALSE(table.find("csf", 3.0)->T2star_ms.has_value());
  const TissueRecord* skin = table.find("skin", 3.0);
  ASSERT_NE(skin, nullptr);
  EXPECT_FALSE(skin->T1_ms || skin->T2_ms || skin->T2star_ms || skin->PD);
  EXPECT_EQ(table.find("white_matter", 7.0), nullptr);
  EXPECT_FALSE(table.has_tissue("brain"));
}

TEST(TissueTable, MalformedCsvNamesTheRowAndColumn) {
  const std::string header = "tissue,field_T,T1_ms,T2_ms,T2star_ms,PD_rel,T1_source,T2_source,T2star_source,"
                             "PD_source,status,notes\n";
  try {
    TissueTable::parse_csv(header + "wm,3,abc,1,1,1,,,,,,\n", "t.csv");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.csv: row 2: column T1_ms"), std::string::npos) << e.what();
  }
  EXPECT_THROW(TissueTable::parse_csv("name,T1\n", "t.csv"), InputError);
  EXPECT_THROW(TissueTable::parse_csv(header + "wm,3,1,1\n", "t.csv"), InputError);
  EXPECT_THROW(TissueTable::parse_csv(header + "wm,3,1,1,1,1,,,,,,\nwm,3,2,2,2,1,,,,,,\n", "t.csv"),
               InputError);
  EXPECT_THROW(TissueTable::parse_csv(header + "wm,3,1,1,1,1,\"open,,,,,\n", "t.csv"), InputError);
}
