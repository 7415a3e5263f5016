// The node process (node/main.cpp): the nodes the configuration names, one or many (issue
// 13, `--node-id 1-32`), as one NodeSet on one SocketCAN socket and one epoll loop, with one
// timerfd armed for the earliest deadline of all nodes (an idle process sleeps), never
// longer than --tick-us. One node is the set of one: there is no second loop.
#pragma once
#include "node/config.hpp"

namespace stepnode::node {

// Runs until SIGINT/SIGTERM; returns the exit status. Throws canio::InterfaceError for an
// interface it cannot use, std::runtime_error for the other failures.
int run_node_process(const NodeConfig& cfg);

}  // namespace stepnode::node
