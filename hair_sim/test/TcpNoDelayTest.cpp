/// setTcpNoDelayOnAccepted (hair_sim/ros/TcpNoDelay.hpp) on real loopback sockets: only the connections
/// accepted on the given port get TCP_NODELAY; the listening socket, the connecting side and another port's
/// connections keep Nagle's algorithm.
#include "hair_sim/ros/TcpNoDelay.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

namespace hair_sim {
namespace {

/// A socket that closes itself.
struct Fd {
  int fd = -1;
  explicit Fd(int f = -1) : fd(f) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

int noDelay(int fd) {
  int on = -1;
  socklen_t size = sizeof on;
  EXPECT_EQ(getsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, &size), 0);
  return on;
}

/// A listening loopback socket (IPv4 or IPv6) on an ephemeral port; *port gets the port.
int listenOn(int family, int* port) {
  const int fd = socket(family, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_storage address{};
  socklen_t length = 0;
  if (family == AF_INET) {
    auto* a = reinterpret_cast<sockaddr_in*>(&address);
    a->sin_family = AF_INET;
    a->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    length = sizeof *a;
  } else {
    auto* a = reinterpret_cast<sockaddr_in6*>(&address);
    a->sin6_family = AF_INET6;
    a->sin6_addr = in6addr_loopback;
    length = sizeof *a;
  }
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), length) != 0 || listen(fd, 4) != 0) {
    close(fd);
    return -1;
  }
  length = sizeof address;
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  *port = ntohs(family == AF_INET ? reinterpret_cast<sockaddr_in*>(&address)->sin_port
                                  : reinterpret_cast<sockaddr_in6*>(&address)->sin6_port);
  return fd;
}

/// Both ends of a loopback connection.
struct Link {
  Fd client;    ///< the side that connected
  Fd accepted;  ///< the listener's side
};

/// A client connected to the listener `server` (same family), and the side `server` accepted.
Link connectTo(int server, int family) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  getsockname(server, reinterpret_cast<sockaddr*>(&address), &length);
  const int fd = socket(family, SOCK_STREAM, 0);
  if (fd < 0 || connect(fd, reinterpret_cast<sockaddr*>(&address), length) != 0) {
    ADD_FAILURE() << "connect failed";
    return Link{Fd(fd), Fd()};
  }
  return Link{Fd(fd), Fd(accept(server, nullptr, nullptr))};
}

TEST(TcpNoDelayTest, OnlyTheConnectionsAcceptedOnThePort) {
  int port = 0, other_port = 0;
  Fd server(listenOn(AF_INET, &port)), other(listenOn(AF_INET, &other_port));
  ASSERT_GE(server.fd, 0);
  ASSERT_GE(other.fd, 0);
  const Link l1 = connectTo(server.fd, AF_INET), l2 = connectTo(server.fd, AF_INET);
  const Link l3 = connectTo(other.fd, AF_INET);
  const Fd &c1 = l1.client, &s1 = l1.accepted, &c2 = l2.client, &s2 = l2.accepted;
  const Fd &c3 = l3.client, &s3 = l3.accepted;
  ASSERT_GE(s1.fd, 0);
  ASSERT_GE(s2.fd, 0);
  ASSERT_GE(s3.fd, 0);
  // Nagle's algorithm is on by default everywhere.
  for (int fd : {server.fd, c1.fd, s1.fd, c2.fd, s2.fd, c3.fd, s3.fd}) EXPECT_EQ(noDelay(fd), 0) << fd;

  const NoDelayResult first = setTcpNoDelayOnAccepted(port);
  EXPECT_TRUE(first.listed);
  EXPECT_EQ(first.accepted, 2);
  EXPECT_EQ(first.set, 2);
  EXPECT_EQ(first.failed, 0);
  EXPECT_NE(noDelay(s1.fd), 0);
  EXPECT_NE(noDelay(s2.fd), 0);
  for (int fd : {server.fd, c1.fd, c2.fd, other.fd, c3.fd, s3.fd}) EXPECT_EQ(noDelay(fd), 0) << fd;

  // Again: nothing left to set; a new connection is.
  const NoDelayResult again = setTcpNoDelayOnAccepted(port);
  EXPECT_EQ(again.accepted, 2);
  EXPECT_EQ(again.set, 0);
  const Link l4 = connectTo(server.fd, AF_INET);
  const Fd &c4 = l4.client, &s4 = l4.accepted;
  const NoDelayResult third = setTcpNoDelayOnAccepted(port);
  EXPECT_EQ(third.accepted, 3);
  EXPECT_EQ(third.set, 1);
  EXPECT_NE(noDelay(s4.fd), 0);
  EXPECT_EQ(noDelay(c4.fd), 0);
}

TEST(TcpNoDelayTest, Ipv6ConnectionsToo) {
  int port = 0;
  Fd server(listenOn(AF_INET6, &port));
  if (server.fd < 0) GTEST_SKIP() << "no IPv6 loopback on this host";
  const Link link = connectTo(server.fd, AF_INET6);
  const Fd &c = link.client, &s = link.accepted;
  ASSERT_GE(s.fd, 0);
  const NoDelayResult r = setTcpNoDelayOnAccepted(port);
  EXPECT_EQ(r.accepted, 1);
  EXPECT_EQ(r.set, 1);
  EXPECT_NE(noDelay(s.fd), 0);
  EXPECT_EQ(noDelay(c.fd), 0);
}

TEST(TcpNoDelayTest, APortOutOfRangeTouchesNothing) {
  int port = 0;
  Fd server(listenOn(AF_INET, &port));
  ASSERT_GE(server.fd, 0);
  const Link link = connectTo(server.fd, AF_INET);
  const Fd& s = link.accepted;
  for (int bad : {0, -1, 65536}) {
    const NoDelayResult r = setTcpNoDelayOnAccepted(bad);
    EXPECT_FALSE(r.listed) << bad;
    EXPECT_EQ(r.accepted, 0) << bad;
    EXPECT_EQ(r.set, 0) << bad;
  }
  EXPECT_EQ(noDelay(s.fd), 0);
}

}  // namespace
}  // namespace hair_sim
