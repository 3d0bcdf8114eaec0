#pragma once
/// TCP_NODELAY on the connections a node accepted on its TCPROS port (hair_sim_node's ~tcp_nodelay).
///
/// roscpp turns Nagle's algorithm off on a publisher's connection only when the subscriber asks for it
/// (ros::TransportHints().tcpNoDelay()); rviz's MarkerArray display does not. With Nagle on, the last part
/// of each large message (hair_markers is about 768 kB) can wait for the acknowledgement of the part before
/// it. roscpp has no publisher-side option, so the node sets the option itself on its sockets.

namespace hair_sim {

/// What setTcpNoDelayOnAccepted found and did.
struct NoDelayResult {
  int accepted = 0;     ///< connected TCP sockets of this process whose local port is `port`
  int set = 0;          ///< of those, the ones that had Nagle's algorithm on and now have TCP_NODELAY
  int failed = 0;       ///< of those, the ones where getting or setting the option failed
  bool listed = false;  ///< whether the process's descriptors could be listed (/proc/self/fd)
};

/// Sets TCP_NODELAY on every connected TCP socket (IPv4 or IPv6) of this process whose local port is
/// `port` (for a ROS node: ros::ConnectionManager::instance()->getTCPPort(), i.e. the connections its
/// subscribers and service clients opened to it). Listening sockets, connections this process opened (an
/// ephemeral local port) and other descriptors are left alone. Linux: the descriptors come from
/// /proc/self/fd.
NoDelayResult setTcpNoDelayOnAccepted(int port);

}  // namespace hair_sim
