// The request head as the server's gate reads it from untrusted clients: where it ends, its
// limits, and the routing facts (request line, a command's Content-Length).

#include "ground_station/http_head.hpp"

#include <gtest/gtest.h>

namespace alight::ground_station {
namespace {

using S = HeadReader::State;

TEST(HeadReaderTest, FindsTheEndOfTheHeadInAnyChunking) {
  const std::string req =
      "POST /api/command HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 12\r\n\r\ncommand=kill";
  for (size_t chunk : {1u, 2u, 7u, 1000u}) {
    HeadReader r(16384, 64);
    size_t used = 0;
    for (size_t i = 0; i < req.size() && r.state() == S::kMore; i += chunk)
      used += r.feed(req.data() + i, std::min(chunk, req.size() - i));
    ASSERT_EQ(r.state(), S::kComplete) << chunk;
    EXPECT_EQ(used, req.size() - 12) << chunk;  // the body is not part of the head
    EXPECT_EQ(r.request_line(), "POST /api/command HTTP/1.1");
    EXPECT_EQ(r.content_length(), 12u);
  }
}

TEST(HeadReaderTest, EnforcesSizeAndHeaderCount) {
  HeadReader big(64, 64);
  const std::string line = "GET / HTTP/1.1\r\nX-Long: " + std::string(100, 'a') + "\r\n\r\n";
  big.feed(line.data(), line.size());
  EXPECT_EQ(big.state(), S::kTooLarge);

  HeadReader many(16384, 4);
  std::string req = "GET / HTTP/1.1\r\n";
  for (int i = 0; i < 5; ++i) req += "X-" + std::to_string(i) + ": 1\r\n";
  req += "\r\n";
  many.feed(req.data(), req.size());
  EXPECT_EQ(many.state(), S::kTooManyHeaders);

  HeadReader four(16384, 4);
  std::string ok = "GET / HTTP/1.1\r\n";
  for (int i = 0; i < 4; ++i) ok += "X-" + std::to_string(i) + ": 1\r\n";
  ok += "\r\n";
  four.feed(ok.data(), ok.size());
  EXPECT_EQ(four.state(), S::kComplete);
}

TEST(HeadReaderTest, ContentLengthMustBeUnambiguous) {
  auto length = [](const std::string& headers) {
    HeadReader r(16384, 64);
    const std::string req = "POST /api/command HTTP/1.1\r\n" + headers + "\r\n";
    r.feed(req.data(), req.size());
    EXPECT_EQ(r.state(), S::kComplete);
    return r.content_length();
  };
  EXPECT_EQ(length(""), 0u);
  EXPECT_EQ(length("content-length:  5 \r\n"), 5u);
  EXPECT_EQ(length("Content-Length: 5\r\nContent-Length: 5\r\n"), 5u);
  EXPECT_FALSE(length("Content-Length: 5\r\nContent-Length: 6\r\n"));
  EXPECT_FALSE(length("Content-Length: -1\r\n"));
  EXPECT_FALSE(length("Content-Length: 99999999999999999999999\r\n"));
  EXPECT_FALSE(length("Transfer-Encoding: chunked\r\n"));
}

TEST(HeadReaderTest, LeadingEmptyLinesAreIgnored) {
  HeadReader r(16384, 64);
  const std::string req = "\r\n\r\nGET / HTTP/1.1\r\n\r\n";
  r.feed(req.data(), req.size());
  EXPECT_EQ(r.state(), S::kComplete);
  EXPECT_EQ(r.request_line(), "GET / HTTP/1.1");
}

TEST(CommandRouteTest, RecognisesOnlyTheCommandEndpoint) {
  EXPECT_TRUE(is_command_request_line("POST /api/command HTTP/1.1"));
  EXPECT_TRUE(is_command_request_line("POST /api/command?x=1 HTTP/1.1"));
  EXPECT_FALSE(is_command_request_line("POST /api/commands HTTP/1.1"));
  EXPECT_FALSE(is_command_request_line("GET /api/command HTTP/1.1"));
  EXPECT_FALSE(is_command_request_line("POST /api/command"));
}

}  // namespace
}  // namespace alight::ground_station
