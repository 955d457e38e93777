// LinkIo's serial transport (issue 16) against a pseudo-terminal: no hardware, but the same
// termios code path as a UART or USB CDC port. A fresh pty slave starts in cooked mode (canonical
// input, echo, CR -> NL, NL -> CR NL on output, XON/XOFF), so every byte arriving unchanged in
// both directions shows that open() put it in raw mode; closing the master is a device that went
// away, which read() must report as an error so that the node closes and reopens it.

#include "mavlink/link_io.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

namespace alight::mavlink {
namespace {

/// A pseudo-terminal pair: the test holds the master, LinkIo opens the slave by its path.
class Pty {
 public:
  Pty() {
    master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0) return;
    const char* name = ptsname(master_);
    if (name) slave_path_ = name;
  }
  ~Pty() { close_master(); }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  bool ok() const { return master_ >= 0 && !slave_path_.empty(); }
  int master() const { return master_; }
  const std::string& slave_path() const { return slave_path_; }
  void close_master() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }

 private:
  int master_ = -1;
  std::string slave_path_;
};

LinkAddress serial(const std::string& device, int baud) {
  LinkAddress a;
  a.kind = LinkAddress::Kind::kSerial;
  a.device = device;
  a.baud = baud;
  return a;
}

/// Every byte value, with the ones a cooked terminal or software flow control would alter or
/// swallow repeated: NUL, LF, CR, XON, XOFF, VINTR (^C), VEOF (^D), VERASE (DEL).
std::vector<uint8_t> awkward_bytes() {
  std::vector<uint8_t> b;
  for (int i = 0; i < 256; ++i) b.push_back(static_cast<uint8_t>(i));
  for (uint8_t c : {0x00, 0x0A, 0x0D, 0x11, 0x13, 0x03, 0x04, 0x7F, 0x0D, 0x0A, 0x00})
    b.push_back(c);
  return b;
}

constexpr auto kGenerous = std::chrono::seconds(20);

/// Reads from the master until `want` bytes have come or kGenerous has passed.
std::vector<uint8_t> read_master(int fd, size_t want) {
  std::vector<uint8_t> got;
  const auto deadline = std::chrono::steady_clock::now() + kGenerous;
  while (got.size() < want && std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    uint8_t buf[512];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) got.insert(got.end(), buf, buf + n);
  }
  return got;
}

/// Reads through LinkIo until `want` bytes have come, it fails, or kGenerous has passed.
std::vector<uint8_t> read_link(LinkIo& io, size_t want, std::string* error) {
  std::vector<uint8_t> got;
  const auto deadline = std::chrono::steady_clock::now() + kGenerous;
  while (got.size() < want && std::chrono::steady_clock::now() < deadline) {
    pollfd p{io.fd(), POLLIN, 0};
    poll(&p, 1, 100);
    uint8_t buf[512];
    const long n = io.read(buf, error);
    if (n < 0) break;
    got.insert(got.end(), buf, buf + n);
  }
  return got;
}

void write_all(int fd, const std::vector<uint8_t>& bytes) {
  size_t done = 0;
  const auto deadline = std::chrono::steady_clock::now() + kGenerous;
  while (done < bytes.size() && std::chrono::steady_clock::now() < deadline) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n > 0) done += static_cast<size_t>(n);
  }
  ASSERT_EQ(done, bytes.size());
}

TEST(LinkIoSerialTest, OpensAPtyInRawModeAtEachSupportedBaud) {
  for (const int baud : kBaudRates) {
    SCOPED_TRACE("baud " + std::to_string(baud));
    Pty pty;
    ASSERT_TRUE(pty.ok());
    {
      // The starting point is a cooked terminal, or this test would show nothing.
      const int probe = ::open(pty.slave_path().c_str(), O_RDWR | O_NOCTTY);
      ASSERT_GE(probe, 0);
      termios t{};
      ASSERT_EQ(tcgetattr(probe, &t), 0);
      EXPECT_TRUE(t.c_lflag & ICANON);
      ::close(probe);
    }
    LinkIo io(serial(pty.slave_path(), baud));
    std::string error;
    ASSERT_TRUE(io.open(&error)) << error;
    ASSERT_TRUE(io.is_open());
    termios t{};
    ASSERT_EQ(tcgetattr(io.fd(), &t), 0);
    speed_t expected = B0;
    switch (baud) {
      case 57600:
        expected = B57600;
        break;
      case 115200:
        expected = B115200;
        break;
      case 230400:
        expected = B230400;
        break;
      case 460800:
        expected = B460800;
        break;
      case 500000:
        expected = B500000;
        break;
      case 576000:
        expected = B576000;
        break;
      case 921600:
        expected = B921600;
        break;
    }
    EXPECT_EQ(cfgetispeed(&t), expected);
    EXPECT_EQ(cfgetospeed(&t), expected);
    EXPECT_FALSE(t.c_lflag & (ICANON | ECHO | ECHONL | ISIG | IEXTEN));
    EXPECT_FALSE(t.c_iflag & (IXON | IXOFF | ICRNL | INLCR | IGNCR | ISTRIP | BRKINT));
    EXPECT_FALSE(t.c_oflag & OPOST);
    EXPECT_EQ(t.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
    EXPECT_FALSE(t.c_cflag & (PARENB | CSTOPB | CRTSCTS));
    EXPECT_TRUE(t.c_cflag & CREAD);
    EXPECT_TRUE(t.c_cflag & CLOCAL);
    // Non-blocking: nothing has come, and read says so instead of waiting.
    uint8_t buf[16];
    EXPECT_EQ(io.read(buf, &error), 0) << error;
  }
}

TEST(LinkIoSerialTest, BytesFromTheLinkReachTheMasterUnchanged) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  LinkIo io(serial(pty.slave_path(), 921600));
  std::string error;
  ASSERT_TRUE(io.open(&error)) << error;
  const std::vector<uint8_t> sent = awkward_bytes();
  size_t done = 0;
  const auto deadline = std::chrono::steady_clock::now() + kGenerous;
  while (done < sent.size() && std::chrono::steady_clock::now() < deadline) {
    const long n = io.write(std::span<const uint8_t>(sent).subspan(done), &error);
    ASSERT_GE(n, 0) << error;
    done += static_cast<size_t>(n);
  }
  ASSERT_EQ(done, sent.size());
  EXPECT_EQ(io.stats().bytes_written, sent.size());
  // Cooked output would turn each LF into CR LF: other bytes in the first sent.size(), and more
  // after them.
  const std::vector<uint8_t> got = read_master(pty.master(), sent.size());
  EXPECT_EQ(got, sent);
  pollfd p{pty.master(), POLLIN, 0};
  EXPECT_EQ(poll(&p, 1, 0), 0);
}

TEST(LinkIoSerialTest, BytesFromTheMasterReachTheLinkUnchangedAndAreNotEchoed) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  LinkIo io(serial(pty.slave_path(), 57600));
  std::string error;
  ASSERT_TRUE(io.open(&error)) << error;
  const std::vector<uint8_t> sent = awkward_bytes();
  write_all(pty.master(), sent);
  const std::vector<uint8_t> got = read_link(io, sent.size(), &error);
  EXPECT_EQ(got, sent) << error;
  EXPECT_EQ(io.stats().bytes_read, sent.size());
  // Echo would send the bytes back to the autopilot.
  pollfd p{pty.master(), POLLIN, 0};
  EXPECT_EQ(poll(&p, 1, 0), 0);
}

TEST(LinkIoSerialTest, AnUnsupportedBaudIsRefusedBeforeTheDeviceIsOpened) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  for (const int baud : {0, 9600, 38400, 1000000, 1500000}) {
    LinkIo io(serial(pty.slave_path(), baud));
    std::string error;
    EXPECT_FALSE(io.open(&error));
    EXPECT_FALSE(io.is_open());
    EXPECT_NE(error.find(pty.slave_path()), std::string::npos) << error;
    EXPECT_NE(error.find("baud " + std::to_string(baud)), std::string::npos) << error;
    EXPECT_NE(error.find("not supported"), std::string::npos) << error;
  }
}

TEST(LinkIoSerialTest, AMissingDeviceOrOneThatIsNoSerialPortGivesAClearError) {
  LinkIo missing(serial("/dev/alight-no-such-tty", 921600));
  std::string error;
  EXPECT_FALSE(missing.open(&error));
  EXPECT_FALSE(missing.is_open());
  EXPECT_NE(error.find("/dev/alight-no-such-tty"), std::string::npos) << error;
  EXPECT_NE(error.find("No such file"), std::string::npos) << error;

  LinkIo not_a_tty(serial("/dev/null", 921600));
  error.clear();
  EXPECT_FALSE(not_a_tty.open(&error));
  EXPECT_FALSE(not_a_tty.is_open());
  EXPECT_NE(error.find("/dev/null"), std::string::npos) << error;
  EXPECT_NE(error.find("not a serial port"), std::string::npos) << error;
}

TEST(LinkIoSerialTest, TheDeviceGoingAwayIsAReadErrorAndItCannotBeReopenedWhileGone) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  LinkIo io(serial(pty.slave_path(), 921600));
  std::string error;
  ASSERT_TRUE(io.open(&error)) << error;
  // Bytes still flow, then the other end closes (a USB adapter unplugged hangs the tty up
  // the same way).
  write_all(pty.master(), {0xFD, 0x00, 0x0A});
  EXPECT_EQ(read_link(io, 3, &error).size(), 3u) << error;
  pty.close_master();
  error.clear();
  long n = 0;
  const auto deadline = std::chrono::steady_clock::now() + kGenerous;
  while (n >= 0 && std::chrono::steady_clock::now() < deadline) {
    pollfd p{io.fd(), POLLIN, 0};
    poll(&p, 1, 100);
    uint8_t buf[64];
    n = io.read(buf, &error);
  }
  EXPECT_EQ(n, -1);
  EXPECT_NE(error.find(pty.slave_path()), std::string::npos) << error;
  // The node closes it and tries again; the pty is gone, so that fails and says why.
  io.close();
  EXPECT_FALSE(io.is_open());
  error.clear();
  EXPECT_FALSE(io.open(&error));
  EXPECT_NE(error.find(pty.slave_path()), std::string::npos) << error;
}

TEST(LinkIoSerialTest, ASecondOpenOfTheSamePortIsRefused) {
  if (geteuid() == 0) GTEST_SKIP() << "TIOCEXCL does not bind root";
  Pty pty;
  ASSERT_TRUE(pty.ok());
  LinkIo first(serial(pty.slave_path(), 921600)), second(serial(pty.slave_path(), 921600));
  std::string error;
  ASSERT_TRUE(first.open(&error)) << error;
  EXPECT_FALSE(second.open(&error));
  EXPECT_NE(error.find(pty.slave_path()), std::string::npos) << error;
}

}  // namespace
}  // namespace alight::mavlink
