// A stock roscpp client of /set_bool: what any ROS 1 C++ node does to call a hetros service.
//
//   g++ -o set_bool_client set_bool_client.cpp $(pkg-config --cflags --libs roscpp)
//   ROS_MASTER_URI=http://127.0.0.1:11311/ ./set_bool_client true
//
// (Debian: apt-get install libroscpp-dev libstd-srvs-dev g++ pkg-config.)
#include <ros/ros.h>
#include <std_srvs/SetBool.h>

#include <cstring>
#include <iostream>

int main(int argc, char** argv) {
  ros::init(argc, argv, "set_bool_client", ros::init_options::AnonymousName);
  ros::NodeHandle node;
  if (!ros::service::waitForService("/set_bool", ros::Duration(20.0))) {
    std::cerr << "/set_bool did not appear within 20 s" << std::endl;
    return 2;
  }
  ros::ServiceClient client = node.serviceClient<std_srvs::SetBool>("/set_bool");
  std_srvs::SetBool call;
  call.request.data = argc > 1 && std::strcmp(argv[1], "true") == 0;
  if (!client.call(call)) {
    std::cerr << "calling /set_bool failed" << std::endl;
    return 1;
  }
  std::cout << "success=" << (call.response.success ? "true" : "false")
            << " message=" << call.response.message << std::endl;
  return 0;
}
