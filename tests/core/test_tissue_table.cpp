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

// The deep nuclei's T2* at 3 T: iron shortens it, so the pallidum (most iron) lies below the
// putamen, the putamen below the caudate, and no nucleus above the cortex; each value names its
// source, and what no source gave stays empty. Their T1 (pallidum, thalamus) lies below the cortex's.
TEST(TissueTable, DeepNucleiT2starAtThreeTeslaFollowIronAndNameTheirSources) {
  const TissueTable& table = TissueTable::builtin();
  const TissueRecord* pallidum = table.find("globus_pallidus", 3.0);
  const TissueRecord* putamen = table.find("putamen", 3.0);
  const TissueRecord* caudate = table.find("caudate_nucleus", 3.0);
  const TissueRecord* thalamus = table.find("thalamus", 3.0);
  const TissueRecord* cortex = table.find("gray_matter", 3.0);
  for (const TissueRecord* r : {pallidum, putamen, caudate, thalamus, cortex}) {
    ASSERT_NE(r, nullptr);
    ASSERT_TRUE(r->T2star_ms.has_value()) << r->tissue;
    EXPECT_FALSE(r->T2star_source.empty()) << r->tissue;
  }
  EXPECT_LT(*pallidum->T2star_ms, *putamen->T2star_ms);
  EXPECT_LT(*putamen->T2star_ms, *caudate->T2star_ms);
  EXPECT_LE(*caudate->T2star_ms, *cortex->T2star_ms);
  EXPECT_LE(*thalamus->T2star_ms, *cortex->T2star_ms);
  EXPECT_NE(pallidum->T2star_source.find("Gelman"), std::string::npos);
  EXPECT_NE(thalamus->T2star_source.find("B0_sim-mapping"), std::string::npos);
  EXPECT_FALSE(thalamus->T2_ms || thalamus->PD);
  EXPECT_FALSE(pallidum->PD);
  // Their T1 at 3 T from one study's R1 (Gelman et al. 2001): the pallidum (iron) shortest, the
  // thalamus (fibre-rich) between it and the cortex.
  for (const TissueRecord* r : {pallidum, thalamus}) {
    ASSERT_TRUE(r->T1_ms.has_value()) << r->tissue;
    EXPECT_NE(r->T1_source.find("Gelman et al. 2001"), std::string::npos) << r->tissue;
  }
  EXPECT_LT(*pallidum->T1_ms, *thalamus->T1_ms);
  EXPECT_LT(*thalamus->T1_ms, *cortex->T1_ms);
  for (const char* name : {"cerebellar_cortex", "cerebellar_white_matter", "pons"}) {
    for (double field : {1.5, 3.0}) {
      const TissueRecord* r = table.find(name, field);
      ASSERT_NE(r, nullptr) << name;
      EXPECT_FALSE(r->T1_ms || r->T2_ms || r->T2star_ms || r->PD) << name << " at " << field << " T";
      EXPECT_EQ(r->status, "no source") << name;
    }
  }
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
