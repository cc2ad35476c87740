// ehc_tag_node: camera image + camera_info -> AprilTag target pose on /ehc/target_pose.
//   rosrun ehc_perception ehc_tag_node _config:=config/perception/tag_node.yaml
// Its parameters: ehc_perception::TagNodeConfig (node_config.h).
// The pose of the configured tag, with its grasp offset, is transformed into the world frame
// (odom) with tf2 at the image time stamp and published as geometry_msgs/PoseStamped. Nothing
// is published for an image without the target (the controller's watchdog handles that).
// An image waits for the camera pose at its stamp on the wall clock
// (ehc_common::waitForTransformWall: at most tf_timeout s, in lock-step ehc_common::kLockstepWallWait s), then is
// dropped with a logged reason (with a lock-step simulator under CPU load the /tf of
// an image's stamp can reach the listener after the image; a tf2 lookup with a timeout waits on
// sim time, which stands still until this node is done). No tf2_ros::MessageFilter: it held a
// message forever when its transformable request was registered just after the transform
// arrived (found in the grasp node, which stalled the lock-step simulator; see ehc_grasp_node).
// With _ack_topic:=<topic> every image is acknowledged there once done with (after its pose is
// published): a lock-step simulator's acknowledgement gate (ehc_common::LockstepAck, demo.sh).
// Work per image is bounded: the subscription keeps the newest image only (one that arrives
// while the node is busy replaces the one waiting), an image that waited longer than stale_after
// in the node is dropped (timer mode), and an image over max_image_pixels or of another size
// than the camera's is dropped before any per-pixel work. What became of the images is logged
// (ehc_perception::FrameCounts) at most every 10 s while images are dropped.
#include "ehc_common/logging.h"
#include "ehc_control/camera_info_msg.h"
#include "ehc_common/lockstep_ack.h"
#include "ehc_perception/frame_counts.h"
#include "ehc_perception/node_config.h"
#include "ehc_perception/tag_detector.h"
#include "ros_conversions.h"

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2_ros/transform_listener.h>

#include <memory>

namespace {

using namespace ehc_perception;
using ehc_control::PinholeCamera;

using ehc_common::kLogThrottle;

class TagNode {
 public:
  TagNode(ros::NodeHandle& nh, const ros::NodeHandle& pnh, const TagNodeConfig& cfg)
      : cfg_(cfg),
        listener_(tf_),
        ack_(pnh, cfg.lockstepInputs()) {
    if (!cfg_.camera_file.empty()) build(ehc_control::loadPinholeCamera(cfg_.camera_file));
    pub_ = nh.advertise<geometry_msgs::PoseStamped>(cfg_.target_topic, 10);
    lockstep_ = !ack_.topic().empty();
    if (lockstep_) ROS_INFO_STREAM("ehc_tag_node: each image acknowledged on " << ack_.topic() << " when done");
    image_sub_ = nh.subscribe(cfg_.image_topic, 1, &TagNode::onImageEvent, this,  // the newest image wins
                              ros::TransportHints().tcpNoDelay());
    if (cfg_.camera_file.empty())
      info_sub_ = nh.subscribe(cfg_.camera_info_topic, 2, &TagNode::onInfo, this, ros::TransportHints().tcpNoDelay());
  }

 private:
  void build(const PinholeCamera& cam) {
    detector_ = std::make_unique<TagDetector>(cfg_.detector, cam);
    detector_->setWantedTags({cfg_.target.tag_id});
    ROS_INFO_STREAM("ehc_tag_node: " << cam.summary());
    if (cam.distortion.size() > 0 && cam.distortion.cwiseAbs().maxCoeff() > 0.0)
      ROS_WARN("ehc_tag_node: the camera has non-zero distortion coefficients; they are ignored "
               "(publish rectified images for accurate tag poses)");
  }

  void onInfo(const sensor_msgs::CameraInfo& msg) {
    try {
      const PinholeCamera cam = ehc_control::cameraFromInfo(msg);
      cam.validate();
      if (detector_ && detector_->camera().sameIntrinsics(cam)) return;
      build(cam);
    } catch (const std::exception& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_tag_node: bad camera_info: " << e.what());
    }
    // The image that came before the first camera_info (a simulator publishes them together).
    if (detector_ && waiting_image_) {
      const sensor_msgs::ImageConstPtr image = waiting_image_;
      waiting_image_.reset();
      onImage(image);
    }
  }

  void onImageEvent(const ros::MessageEvent<const sensor_msgs::Image>& event) {
    const sensor_msgs::ImageConstPtr image = event.getConstMessage();
    const double waited = (ros::Time::now() - event.getReceiptTime()).toSec();
    if (!lockstep_ && waited > cfg_.stale_after) {
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_tag_node: image at " << image->header.stamp << " dropped: it waited "
                                                << waited << " s in the node (stale_after " << cfg_.stale_after << " s)");
      count(FrameOutcome::Stale);
      ack_.done(image->header.stamp);
      return;
    }
    onImage(image);
  }

  void count(FrameOutcome o) { ros_conv::countFrame(&counts_, o, "ehc_tag_node"); }

  void onImage(const sensor_msgs::ImageConstPtr& image) {
    if (!detector_) {
      // No camera_info yet: the newest such image waits for it (acknowledged when processed).
      if (waiting_image_) ack_.done(waiting_image_->header.stamp);
      waiting_image_ = image;
      ROS_WARN_THROTTLE(kLogThrottle, "ehc_tag_node: no camera_info yet, the image waits for it");
      return;
    }
    count(process(*image));
    ack_.done(image->header.stamp);  // after the target pose: the simulator steps on
  }

  /// Whether an image of this size is read at all: within max_image_pixels and the camera's
  /// size (checked on the header, before any per-pixel work).
  FrameOutcome checkSize(const sensor_msgs::Image& msg) const {
    const std::uint64_t pixels = std::uint64_t{msg.width} * msg.height;
    if (pixels > static_cast<std::uint64_t>(cfg_.max_image_pixels)) {
      ROS_ERROR_THROTTLE(kLogThrottle, "ehc_tag_node: %ux%u image dropped: over max_image_pixels (%d)", msg.width,
                         msg.height, cfg_.max_image_pixels);
      return FrameOutcome::Oversized;
    }
    const PinholeCamera& cam = detector_->camera();
    if (static_cast<int>(msg.width) != cam.width || static_cast<int>(msg.height) != cam.height) {
      ROS_ERROR_THROTTLE(kLogThrottle, "ehc_tag_node: %ux%u image dropped: the camera is %dx%d", msg.width, msg.height,
                         cam.width, cam.height);
      return FrameOutcome::Malformed;
    }
    return FrameOutcome::Processed;
  }

  FrameOutcome process(const sensor_msgs::Image& msg) {
    if (!detector_) {
      ROS_WARN_THROTTLE(kLogThrottle, "ehc_tag_node: no camera_info yet, image ignored");
      return FrameOutcome::Malformed;
    }
    const FrameOutcome size = checkSize(msg);
    if (size != FrameOutcome::Processed) return size;
    // The camera pose at the image stamp: the detector's prior for ambiguous tag poses, and the
    // target in the world.
    const std::string cam_frame = cfg_.camera_frame.empty() ? msg.header.frame_id : cfg_.camera_frame;
    const double wait = lockstep_ ? ehc_common::kLockstepWallWait : cfg_.tf_timeout;
    if (!ehc_common::waitForTransformWall(tf_, cfg_.world_frame, cam_frame, msg.header.stamp, wait)) {
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_tag_node: image at " << msg.header.stamp << " dropped: no camera pose ('"
                                                << cam_frame << "' in '" << cfg_.world_frame << "') at its stamp after "
                                                << wait << " wall s");
      return FrameOutcome::NoCameraPose;
    }
    try {
      ros_conv::imageToGray(msg, &gray_);
    } catch (const std::invalid_argument& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_tag_node: image dropped: " << e.what());
      return FrameOutcome::Malformed;
    }
    try {
      const Eigen::Isometry3d T_world_cam =
          tf2::transformToEigen(tf_.lookupTransform(cfg_.world_frame, cam_frame, msg.header.stamp));
      const std::vector<TagDetection> dets = detector_->detect(gray_, T_world_cam);
      Eigen::Isometry3d T_world;
      if (!findTargetInWorld(dets, cfg_.target, T_world_cam, &T_world)) {
        ROS_DEBUG_THROTTLE(kLogThrottle, "ehc_tag_node: target tag %d not seen (%zu tags)",
                           cfg_.target.tag_id, dets.size());
        return FrameOutcome::Processed;
      }
      geometry_msgs::PoseStamped out;
      out.header.stamp = msg.header.stamp;
      out.header.frame_id = cfg_.world_frame;
      out.pose = ros_conv::toPose(T_world);
      pub_.publish(out);
      return FrameOutcome::Processed;
    } catch (const std::exception& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_tag_node: image dropped: " << e.what());
      return FrameOutcome::Failed;
    }
  }

  TagNodeConfig cfg_;
  tf2_ros::Buffer tf_;
  tf2_ros::TransformListener listener_;
  std::unique_ptr<TagDetector> detector_;
  vpImage<unsigned char> gray_;
  ros::Subscriber image_sub_;
  bool lockstep_ = false;  ///< _ack_topic set: a lock-step simulator waits for every image
  ros::Publisher pub_;
  ehc_common::LockstepAck ack_;
  sensor_msgs::ImageConstPtr waiting_image_;  ///< an image that came before the first camera_info
  ros::Subscriber info_sub_;
  FrameCounts counts_{"images"};  ///< what became of the images (logged)
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ehc_tag_node");
  ros::NodeHandle nh, pnh("~");
  std::string config;
  if (!pnh.getParam("config", config)) {
    ROS_FATAL("ehc_tag_node: missing _config:=<file.yaml> (see config/perception/tag_node.yaml)");
    return 2;
  }
  try {
    const TagNodeConfig cfg = loadTagNodeConfig(config);
    ROS_INFO_STREAM(cfg.summary());
    TagNode node(nh, pnh, cfg);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("ehc_tag_node: " << e.what());
    return 2;
  }
  return 0;
}
