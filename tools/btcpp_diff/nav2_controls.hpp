// Nav2's four controls and decorators of navigate_to_pose_w_replanning_and_recovery.xml (RecoveryNode,
// PipelineSequence, RoundRobin, RateController), transcribed from Nav2's nav2_behavior_tree/plugins
// (ros-navigation/navigation2, commit a3a97043ee93d92fe8d70ec56d183933169beb1c, Apache-2.0) with nothing of ROS
// but the logic: the differential driver registers them (--nav2) in place of Nav2's library, as the Nav2 tree
// needs them and BT.CPP cannot load Nav2's plugins here. Their Python twins are
// tests/data/nav2/nav2_controls.py; keep the two equal. RateController reads the wall clock, as Nav2's does.

#pragma once

#include <behaviortree_cpp/bt_factory.h>

#include <chrono>
#include <sstream>
#include <stdexcept>
#include <string>

namespace nav2
{

class RecoveryNode : public BT::ControlNode
{
public:
  RecoveryNode(const std::string& name, const BT::NodeConfig& conf) : BT::ControlNode(name, conf)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<int>("number_of_retries", 1, "Number of retries") };
  }

  BT::NodeStatus tick() override
  {
    getInput("number_of_retries", number_of_retries_);
    const unsigned children_count = children_nodes_.size();
    if(children_count != 2)
    {
      throw BT::BehaviorTreeException("Recovery Node '" + name() + "' must only have 2 children.");
    }
    setStatus(BT::NodeStatus::RUNNING);
    while(current_child_idx_ < children_count && retry_count_ <= number_of_retries_)
    {
      TreeNode* child_node = children_nodes_[current_child_idx_];
      const BT::NodeStatus child_status = child_node->executeTick();
      if(current_child_idx_ == 0)
      {
        switch(child_status)
        {
          case BT::NodeStatus::SKIPPED:
            halt();
            return BT::NodeStatus::SKIPPED;
          case BT::NodeStatus::SUCCESS:
            ControlNode::haltChild(1);
            halt();
            return BT::NodeStatus::SUCCESS;
          case BT::NodeStatus::RUNNING:
            return BT::NodeStatus::RUNNING;
          case BT::NodeStatus::FAILURE:
            if(retry_count_ < number_of_retries_)
            {
              ControlNode::haltChild(0);
              current_child_idx_++;
              break;
            }
            halt();
            return BT::NodeStatus::FAILURE;
          default:
            throw BT::LogicError("A child node must never return IDLE");
        }
      }
      else if(current_child_idx_ == 1)
      {
        switch(child_status)
        {
          case BT::NodeStatus::SKIPPED:
            current_child_idx_ = 0;
            ControlNode::haltChild(1);
            return BT::NodeStatus::FAILURE;
          case BT::NodeStatus::RUNNING:
            return child_status;
          case BT::NodeStatus::SUCCESS:
            ControlNode::haltChild(1);
            retry_count_++;
            current_child_idx_ = 0;
            break;
          case BT::NodeStatus::FAILURE:
            halt();
            return BT::NodeStatus::FAILURE;
          default:
            throw BT::LogicError("A child node must never return IDLE");
        }
      }
    }
    halt();
    return BT::NodeStatus::FAILURE;
  }

  void halt() override
  {
    ControlNode::halt();
    retry_count_ = 0;
    current_child_idx_ = 0;
  }

private:
  unsigned current_child_idx_ = 0;
  int number_of_retries_ = 1;
  int retry_count_ = 0;
};

class PipelineSequence : public BT::ControlNode
{
public:
  PipelineSequence(const std::string& name, const BT::NodeConfig& conf) : BT::ControlNode(name, conf)
  {}

  static BT::PortsList providedPorts()
  {
    return {};
  }

  BT::NodeStatus tick() override
  {
    unsigned skipped_count = 0;
    for(std::size_t i = 0; i < children_nodes_.size(); ++i)
    {
      auto status = children_nodes_[i]->executeTick();
      switch(status)
      {
        case BT::NodeStatus::FAILURE:
          ControlNode::haltChildren();
          last_child_ticked_ = 0;
          return status;
        case BT::NodeStatus::SKIPPED:
          skipped_count++;
          break;
        case BT::NodeStatus::SUCCESS:
          break;
        case BT::NodeStatus::RUNNING:
          if(i >= last_child_ticked_)
          {
            last_child_ticked_ = i;
            return status;
          }
          break;
        default: {
          std::stringstream error_msg;
          error_msg << "Invalid node status. Received status " << status << "from child "
                    << children_nodes_[i]->name();
          throw std::runtime_error(error_msg.str());
        }
      }
    }
    ControlNode::haltChildren();
    last_child_ticked_ = 0;
    if(skipped_count == children_nodes_.size())
    {
      return BT::NodeStatus::SKIPPED;
    }
    return BT::NodeStatus::SUCCESS;
  }

  void halt() override
  {
    BT::ControlNode::halt();
    last_child_ticked_ = 0;
  }

private:
  std::size_t last_child_ticked_ = 0;
};

class RoundRobin : public BT::ControlNode
{
public:
  RoundRobin(const std::string& name, const BT::NodeConfig& conf) : BT::ControlNode(name, conf)
  {
    getInput("wrap_around", wrap_around_);
  }

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<bool>("wrap_around", false, "Controls wrap-around behavior") };
  }

  BT::NodeStatus tick() override
  {
    const auto num_children = children_nodes_.size();
    setStatus(BT::NodeStatus::RUNNING);
    unsigned num_skipped_children = 0;
    while(num_failed_children_ + num_skipped_children < num_children)
    {
      TreeNode* child_node = children_nodes_[current_child_idx_];
      const BT::NodeStatus child_status = child_node->executeTick();
      if(child_status != BT::NodeStatus::RUNNING)
      {
        if(++current_child_idx_ == num_children)
        {
          if(wrap_around_)
          {
            current_child_idx_ = 0;
          }
          else
          {
            if(child_status == BT::NodeStatus::SKIPPED)
            {
              num_skipped_children++;
            }
            else if(child_status == BT::NodeStatus::FAILURE)
            {
              num_failed_children_++;
            }
            break;
          }
        }
      }
      switch(child_status)
      {
        case BT::NodeStatus::SUCCESS:
          num_failed_children_ = 0;
          ControlNode::haltChildren();
          return BT::NodeStatus::SUCCESS;
        case BT::NodeStatus::FAILURE:
          num_failed_children_++;
          break;
        case BT::NodeStatus::SKIPPED:
          num_skipped_children++;
          break;
        case BT::NodeStatus::RUNNING:
          return BT::NodeStatus::RUNNING;
        default:
          throw BT::LogicError("Invalid status return from BT node");
      }
    }
    const bool all_skipped = (num_skipped_children == num_children);
    halt();
    return all_skipped ? BT::NodeStatus::SKIPPED : BT::NodeStatus::FAILURE;
  }

  void halt() override
  {
    ControlNode::halt();
    current_child_idx_ = 0;
    num_failed_children_ = 0;
  }

private:
  unsigned int current_child_idx_ = 0;
  unsigned int num_failed_children_ = 0;
  bool wrap_around_ = false;
};

class RateController : public BT::DecoratorNode
{
public:
  RateController(const std::string& name, const BT::NodeConfig& conf) : BT::DecoratorNode(name, conf)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<double>("hz", 10.0, "Rate") };
  }

  BT::NodeStatus tick() override
  {
    if(!BT::isStatusActive(status()))
    {
      double hz = 1.0;
      getInput("hz", hz);
      period_ = 1.0 / hz;
      start_ = std::chrono::high_resolution_clock::now();
      first_time_ = true;
    }
    setStatus(BT::NodeStatus::RUNNING);
    auto elapsed = std::chrono::high_resolution_clock::now() - start_;
    auto seconds = std::chrono::duration_cast<std::chrono::duration<float>>(elapsed);
    if(first_time_ || (child_node_->status() == BT::NodeStatus::RUNNING) || seconds.count() >= period_)
    {
      first_time_ = false;
      const BT::NodeStatus child_state = child_node_->executeTick();
      switch(child_state)
      {
        case BT::NodeStatus::SKIPPED:
        case BT::NodeStatus::RUNNING:
        case BT::NodeStatus::FAILURE:
          return child_state;
        case BT::NodeStatus::SUCCESS:
          start_ = std::chrono::high_resolution_clock::now();
          return BT::NodeStatus::SUCCESS;
        default:
          return BT::NodeStatus::FAILURE;
      }
    }
    return status();
  }

private:
  std::chrono::time_point<std::chrono::high_resolution_clock> start_;
  double period_ = 1.0;
  bool first_time_ = false;
};

inline void registerAll(BT::BehaviorTreeFactory& factory)
{
  factory.registerNodeType<RecoveryNode>("RecoveryNode");
  factory.registerNodeType<PipelineSequence>("PipelineSequence");
  factory.registerNodeType<RoundRobin>("RoundRobin");
  factory.registerNodeType<RateController>("RateController");
}

}  // namespace nav2
