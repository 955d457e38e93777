// CRC-16/MCRF4XX and CRC_EXTRA (mavlink.io/en/guide/serialization.html, "Checksum", "CRC_EXTRA
// Calculation").

#include "mavlink/crc.hpp"

#include <gtest/gtest.h>

#include <string_view>

#include "mavlink/messages.hpp"

namespace alight::mavlink {
namespace {

TEST(MavlinkCrc, CheckValueOfTheCatalogue) {
  // The CRC catalogue's check value of CRC-16/MCRF4XX over "123456789".
  constexpr std::string_view digits = "123456789";
  EXPECT_EQ(crc16_mcrf4xx(reinterpret_cast<const uint8_t*>(digits.data()), digits.size()), 0x6F91);
  EXPECT_EQ(crc16_mcrf4xx(nullptr, 0), 0xFFFF);
}

TEST(MavlinkCrc, AccumulatesInPieces) {
  const uint8_t data[] = {0xFD, 0x09, 0x00, 0x00, 0x2A, 0x01, 0xC8, 0x00, 0x00, 0x00, 0x07};
  uint16_t crc = kCrcInit;
  for (uint8_t b : data) crc = crc_accumulate(b, crc);
  EXPECT_EQ(crc, crc16_mcrf4xx(data, sizeof data));
  EXPECT_EQ(crc_accumulate(data + 4, 7, crc_accumulate(data, 4, kCrcInit)), crc);
}

// CRC_EXTRA recomputed from each message's field list (names, types, array lengths in wire
// order) equals the value published with the message set; also checked at compile time.
TEST(MavlinkCrc, CrcExtraFromTheFieldListsIsThePublishedOne) {
  struct Published {
    uint32_t id;
    uint8_t crc_extra;
  };
  // Computed from common.xml, minimal.xml and standard.xml with the algorithm of serialization.html
  // (a script over the XML, not this code); they are also the values every MAVLink library ships.
  const Published published[] = {{0, 50},    {1, 124},  {31, 246}, {32, 185}, {76, 152},  {77, 143},
                                 {82, 49},   {84, 143}, {105, 93}, {111, 34}, {138, 109}, {253, 83},
                                 {331, 91},  {26, 170}, {48, 41},  {49, 39},  {108, 32},  {115, 4},
                                 {245, 130}, {256, 71}, {20, 214}, {22, 220}, {148, 178}};
  int seen = 0;
  for_each_message_type([&](auto tag) {
    using M = decltype(tag);
    constexpr auto layout = layout_of<M>();
    SCOPED_TRACE(std::string(M::kName));
    EXPECT_TRUE(layout.wire_order_ok());
    EXPECT_EQ(layout.crc_extra(), M::kCrcExtra);
    EXPECT_EQ(layout.base_length(), M::kBaseLength);
    EXPECT_EQ(layout.max_length(), M::kMaxLength);
    bool found = false;
    for (const auto& p : published)
      if (p.id == M::kId) {
        found = true;
        EXPECT_EQ(M::kCrcExtra, p.crc_extra);
      }
    EXPECT_TRUE(found);
    const MessageInfo* info = find_message(M::kId);
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(info->crc_extra, M::kCrcExtra);
    EXPECT_EQ(info->name, M::kName);
    ++seen;
  });
  EXPECT_EQ(seen, 23);
  EXPECT_EQ(find_message(2), nullptr);
  EXPECT_EQ(find_message(0xFFFFFF), nullptr);
}

}  // namespace
}  // namespace alight::mavlink
