"""A rospy node using an API hetros has no counterpart for (a check case)."""
import rospy
from std_msgs.msg import String


class Greeter(rospy.SubscribeListener):
    def peer_subscribe(self, topic_name, topic_publish, peer_publish):
        peer_publish(String("welcome"))


rospy.init_node("greeter")
rospy.Publisher("chatter", String, subscriber_listener=Greeter(), queue_size=10)
rospy.spin()
