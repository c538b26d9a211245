// A stock roscpp subscriber, as a ROS 1 user writes one: prints what it hears on /chatter,
// then leaves after `count` messages (argv[1]).
#include <cstdlib>
#include <ros/ros.h>
#include <std_msgs/String.h>

static int heard = 0;
static int wanted = 5;

static void chatter(const std_msgs::String::ConstPtr& message) {
  std::printf("I heard: [%s]\n", message->data.c_str());
  std::fflush(stdout);
  if (++heard >= wanted) ros::shutdown();
}

int main(int argc, char** argv) {
  ros::init(argc, argv, "roscpp_listener");
  if (argc > 1) wanted = std::atoi(argv[1]);
  ros::NodeHandle node;
  ros::Subscriber subscription = node.subscribe("/chatter", 10, chatter);
  ros::spin();
  return heard >= wanted ? 0 : 1;
}
