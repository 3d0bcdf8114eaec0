#include "hair_sim/ros/TcpNoDelay.hpp"

#include <arpa/inet.h>
#include <dirent.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <cstdlib>

namespace hair_sim {

namespace {

/// The local or peer port of a TCP socket over IPv4 or IPv6, -1 when fd is not one or has none.
int portOf(int fd, bool peer) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  sockaddr* a = reinterpret_cast<sockaddr*>(&address);
  if ((peer ? getpeername(fd, a, &length) : getsockname(fd, a, &length)) != 0) return -1;
  if (address.ss_family == AF_INET) return ntohs(reinterpret_cast<const sockaddr_in*>(a)->sin_port);
  if (address.ss_family == AF_INET6) return ntohs(reinterpret_cast<const sockaddr_in6*>(a)->sin6_port);
  return -1;
}

}  // namespace

NoDelayResult setTcpNoDelayOnAccepted(int port) {
  NoDelayResult result;
  if (port <= 0 || port > 65535) return result;
  DIR* dir = opendir("/proc/self/fd");
  if (!dir) return result;
  result.listed = true;
  const int own = dirfd(dir);
  while (const dirent* entry = readdir(dir)) {
    char* end = nullptr;
    const long value = std::strtol(entry->d_name, &end, 10);
    if (end == entry->d_name || *end != '\0' || value < 0 || value == own) continue;
    const int fd = static_cast<int>(value);
    int type = 0;
    socklen_t size = sizeof type;
    if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &size) != 0 || type != SOCK_STREAM) continue;
    // Accepted on `port`: bound to it and connected (a listening socket has no peer).
    if (portOf(fd, false) != port || portOf(fd, true) < 0) continue;
    ++result.accepted;
    int on = 0;
    size = sizeof on;
    if (getsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, &size) != 0) {
      ++result.failed;
      continue;
    }
    if (on) continue;
    on = 1;
    if (setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on) != 0) {
      ++result.failed;
      continue;
    }
    ++result.set;
  }
  closedir(dir);
  return result;
}

}  // namespace hair_sim
