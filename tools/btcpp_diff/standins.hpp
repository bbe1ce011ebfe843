// Stand-ins for other projects' nodes, written the way a BT.CPP user writes them (sync, stateful and
// condition nodes, a custom port type, controls and decorators of their own), so trees taken from such
// projects can be run through BehaviorTree.CPP by the differential driver. Their twins, written with
// bt_grasp's public plugin API, are tests/tree_conformance/standins.py; keep the two equal.
//
// The "world" a stand-in acts on lives in the root blackboard (`@door_open`, `@planner_failures`, ...),
// set by the tree's own scripts, so that no state survives from one tree to the next and every outcome
// is visible in the recorded blackboard. No stand-in reads the clock: durations are counted in ticks.
//
// Shapes taken from: BT.CPP's tutorials (SaySomething, ThinkWhatToSay, CalculateGoal/PrintTarget with a
// custom type, BatteryOK/MoveBase, the CrossDoor nodes) and Nav2's navigation trees (ComputePathToPose,
// FollowPath, ClearEntireCostmap, GoalUpdated, Spin, Wait, BackUp, RecoveryNode, PipelineSequence,
// RoundRobin, RateController, GoalUpdater). This file is bt_grasp's own code.

#pragma once

#include <behaviortree_cpp/bt_factory.h>

#include <cmath>
#include <string>

// A 2-D position written "x;y" in a tree file (BT.CPP tutorial 3's custom port type).
struct Position2D
{
  double x = 0;
  double y = 0;
};

namespace BT
{
template <>
inline Position2D convertFromString(StringView str)
{
  auto parts = splitString(str, ';');
  if(parts.size() != 2)
  {
    throw RuntimeError("invalid input)");
  }
  Position2D output;
  output.x = convertFromString<double>(parts[0]);
  output.y = convertFromString<double>(parts[1]);
  return output;
}
}  // namespace BT

namespace standins
{
using BT::NodeStatus;

template <typename T>
T rootValue(const BT::TreeNode& node, const std::string& key, T fallback)
{
  T value = fallback;
  if(!node.config().blackboard->get<T>("@" + key, value))
  {
    return fallback;
  }
  return value;
}

template <typename T>
void setRoot(const BT::TreeNode& node, const std::string& key, const T& value)
{
  node.config().blackboard->set<T>("@" + key, value);
}

// Appends `text` to the root entry `said` ("a|b|c"): what the robot said, for the comparison.
inline void say(const BT::TreeNode& node, const std::string& text)
{
  std::string said = rootValue<std::string>(node, "said", "");
  setRoot<std::string>(node, "said", said.empty() ? text : said + "|" + text);
}

// Takes one from a positive integer root entry; true when it did (a scripted failure is due).
inline bool takeOne(const BT::TreeNode& node, const std::string& key)
{
  const int left = rootValue<int>(node, key, 0);
  if(left <= 0)
  {
    return false;
  }
  setRoot<int>(node, key, left - 1);
  return true;
}

// ---------------------------------------------------------------- BT.CPP tutorials

class SaySomething : public BT::SyncActionNode
{
public:
  SaySomething(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("message") };
  }
  NodeStatus tick() override
  {
    auto message = getInput<std::string>("message");
    if(!message)
    {
      throw BT::RuntimeError("missing required input [message]: ", message.error());
    }
    say(*this, message.value());
    return NodeStatus::SUCCESS;
  }
};

class ThinkWhatToSay : public BT::SyncActionNode
{
public:
  ThinkWhatToSay(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::OutputPort<std::string>("text") };
  }
  NodeStatus tick() override
  {
    setOutput("text", std::string("The answer is 42"));
    return NodeStatus::SUCCESS;
  }
};

class CalculateGoal : public BT::SyncActionNode
{
public:
  CalculateGoal(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::OutputPort<Position2D>("goal") };
  }
  NodeStatus tick() override
  {
    setOutput("goal", Position2D{ 1.1, 2.3 });
    return NodeStatus::SUCCESS;
  }
};

class PrintTarget : public BT::SyncActionNode
{
public:
  PrintTarget(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<Position2D>("target") };
  }
  NodeStatus tick() override
  {
    auto target = getInput<Position2D>("target");
    if(!target)
    {
      throw BT::RuntimeError("missing required input [target]: ", target.error());
    }
    char text[64];
    std::snprintf(text, sizeof(text), "target %.1f %.1f", target->x, target->y);
    say(*this, text);
    return NodeStatus::SUCCESS;
  }
};

// SUCCESS while the battery (its port, by default the entry `battery`) is at least 20.
class BatteryOK : public BT::ConditionNode
{
public:
  BatteryOK(const std::string& name, const BT::NodeConfig& config) : BT::ConditionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<int>("level", "{battery}", "charge in percent") };
  }
  NodeStatus tick() override
  {
    auto level = getInput<int>("level");
    if(!level)
    {
      throw BT::RuntimeError("BatteryOK: ", level.error());
    }
    return level.value() >= 20 ? NodeStatus::SUCCESS : NodeStatus::FAILURE;
  }
};

// Drives to `goal` in `steps` ticks (RUNNING meanwhile); counts its halts in `@move_halts`.
class MoveBase : public BT::StatefulActionNode
{
public:
  MoveBase(const std::string& name, const BT::NodeConfig& config) : BT::StatefulActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<Position2D>("goal"), BT::InputPort<int>("steps", 2, "ticks to arrive") };
  }
  NodeStatus onStart() override
  {
    if(!getInput<Position2D>("goal"))
    {
      throw BT::RuntimeError("missing required input [goal]");
    }
    done_ = 0;
    return NodeStatus::RUNNING;
  }
  NodeStatus onRunning() override
  {
    if(++done_ >= getInput<int>("steps").value())
    {
      setRoot<int>(*this, "moves", rootValue<int>(*this, "moves", 0) + 1);
      return NodeStatus::SUCCESS;
    }
    return NodeStatus::RUNNING;
  }
  void onHalted() override
  {
    setRoot<int>(*this, "move_halts", rootValue<int>(*this, "move_halts", 0) + 1);
  }

private:
  int done_ = 0;
};

// The CrossDoor nodes: the door's state is `@door_open`, `@door_locked`; PickLock opens the lock at
// its third attempt.
class IsDoorClosed : public BT::ConditionNode
{
public:
  IsDoorClosed(const std::string& name, const BT::NodeConfig& config) : BT::ConditionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    return rootValue<bool>(*this, "door_open", false) ? NodeStatus::FAILURE : NodeStatus::SUCCESS;
  }
};

class PassThroughDoor : public BT::SyncActionNode
{
public:
  PassThroughDoor(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    if(!rootValue<bool>(*this, "door_open", false))
    {
      return NodeStatus::FAILURE;
    }
    setRoot<bool>(*this, "passed", true);
    return NodeStatus::SUCCESS;
  }
};

class OpenDoor : public BT::SyncActionNode
{
public:
  OpenDoor(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    if(rootValue<bool>(*this, "door_locked", false))
    {
      return NodeStatus::FAILURE;
    }
    setRoot<bool>(*this, "door_open", true);
    return NodeStatus::SUCCESS;
  }
};

class PickLock : public BT::SyncActionNode
{
public:
  PickLock(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    const int attempts = rootValue<int>(*this, "pick_attempts", 0) + 1;
    setRoot<int>(*this, "pick_attempts", attempts);
    if(attempts < 3)
    {
      return NodeStatus::FAILURE;
    }
    setRoot<bool>(*this, "door_locked", false);
    setRoot<bool>(*this, "door_open", true);
    return NodeStatus::SUCCESS;
  }
};

class SmashDoor : public BT::SyncActionNode
{
public:
  SmashDoor(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    return NodeStatus::FAILURE;
  }
};

// ---------------------------------------------------------------- Nav2-like nodes

// One tick of RUNNING, then a path to `goal`; fails (error code 204) while `@planner_failures` > 0.
class ComputePathToPose : public BT::StatefulActionNode
{
public:
  ComputePathToPose(const std::string& name, const BT::NodeConfig& config)
    : BT::StatefulActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("goal"), BT::InputPort<std::string>("planner_id", "GridBased", ""),
             BT::OutputPort<std::string>("path"), BT::OutputPort<int>("error_code_id") };
  }
  NodeStatus onStart() override
  {
    return NodeStatus::RUNNING;
  }
  NodeStatus onRunning() override
  {
    setRoot<int>(*this, "plans", rootValue<int>(*this, "plans", 0) + 1);
    if(takeOne(*this, "planner_failures"))
    {
      setOutput("error_code_id", 204);
      return NodeStatus::FAILURE;
    }
    const std::string goal = getInput<std::string>("goal").value();
    setOutput("path", getInput<std::string>("planner_id").value() + ":" + goal);
    setOutput("error_code_id", 0);
    return NodeStatus::SUCCESS;
  }
  void onHalted() override
  {}
};

// RUNNING for `@follow_ticks` ticks (2 when unset), then SUCCESS; fails while `@follow_failures` > 0.
class FollowPath : public BT::StatefulActionNode
{
public:
  FollowPath(const std::string& name, const BT::NodeConfig& config) : BT::StatefulActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("path"), BT::InputPort<std::string>("controller_id", "FollowPath", ""),
             BT::OutputPort<int>("error_code_id") };
  }
  NodeStatus onStart() override
  {
    if(getInput<std::string>("path").value().empty())
    {
      return NodeStatus::FAILURE;
    }
    done_ = 0;
    return NodeStatus::RUNNING;
  }
  NodeStatus onRunning() override
  {
    if(++done_ < rootValue<int>(*this, "follow_ticks", 2))
    {
      return NodeStatus::RUNNING;
    }
    if(takeOne(*this, "follow_failures"))
    {
      setOutput("error_code_id", 106);
      return NodeStatus::FAILURE;
    }
    setRoot<int>(*this, "arrivals", rootValue<int>(*this, "arrivals", 0) + 1);
    setOutput("error_code_id", 0);
    return NodeStatus::SUCCESS;
  }
  void onHalted() override
  {
    setRoot<int>(*this, "follow_halts", rootValue<int>(*this, "follow_halts", 0) + 1);
  }

private:
  int done_ = 0;
};

class ClearEntireCostmap : public BT::SyncActionNode
{
public:
  ClearEntireCostmap(const std::string& name, const BT::NodeConfig& config)
    : BT::SyncActionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("service_name") };
  }
  NodeStatus tick() override
  {
    setRoot<int>(*this, "clears", rootValue<int>(*this, "clears", 0) + 1);
    return NodeStatus::SUCCESS;
  }
};

// SUCCESS once per pending `@goal_updates`.
class GoalUpdated : public BT::ConditionNode
{
public:
  GoalUpdated(const std::string& name, const BT::NodeConfig& config) : BT::ConditionNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    return takeOne(*this, "goal_updates") ? NodeStatus::SUCCESS : NodeStatus::FAILURE;
  }
};

// A recovery behaviour: RUNNING for `ticks` ticks, then SUCCESS (FAILURE while `@<name>_failures` > 0);
// records its name in `@said`.
class Behavior : public BT::StatefulActionNode
{
public:
  Behavior(const std::string& name, const BT::NodeConfig& config) : BT::StatefulActionNode(name, config)
  {}
  NodeStatus onStart() override
  {
    done_ = 0;
    return ticks() > 0 ? NodeStatus::RUNNING : finish();
  }
  NodeStatus onRunning() override
  {
    return ++done_ < ticks() ? NodeStatus::RUNNING : finish();
  }
  void onHalted() override
  {
    say(*this, "halted " + registrationName());
  }

protected:
  virtual int ticks() const = 0;

private:
  NodeStatus finish()
  {
    if(takeOne(*this, registrationName() + "_failures"))
    {
      return NodeStatus::FAILURE;
    }
    say(*this, registrationName());
    return NodeStatus::SUCCESS;
  }
  int done_ = 0;
};

class Spin : public Behavior
{
public:
  using Behavior::Behavior;
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<double>("spin_dist", 1.57, "rad") };
  }

protected:
  int ticks() const override
  {
    return 1;
  }
};

class Wait : public Behavior
{
public:
  using Behavior::Behavior;
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<double>("wait_duration", 1.0, "seconds (one tick each)") };
  }

protected:
  int ticks() const override
  {
    return static_cast<int>(getInput<double>("wait_duration").value());
  }
};

class BackUp : public Behavior
{
public:
  using Behavior::Behavior;
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<double>("backup_dist", 0.15, "m"), BT::InputPort<double>("backup_speed", 0.025, "m/s") };
  }

protected:
  int ticks() const override
  {
    return 0;
  }
};

// Two children: on the first child's FAILURE, tick the second (the recovery) and, if it succeeds, the
// first again, at most `number_of_retries` times (Nav2's RecoveryNode).
class RecoveryNode : public BT::ControlNode
{
public:
  RecoveryNode(const std::string& name, const BT::NodeConfig& config) : BT::ControlNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<int>("number_of_retries", 1, "") };
  }
  NodeStatus tick() override
  {
    const int retries = getInput<int>("number_of_retries").value();
    if(childrenCount() != 2)
    {
      throw BT::RuntimeError("RecoveryNode needs exactly 2 children");
    }
    setStatus(NodeStatus::RUNNING);
    while(current_ < 2 && retry_count_ <= retries)
    {
      const NodeStatus status = children_nodes_[current_]->executeTick();
      if(current_ == 0)
      {
        if(status == NodeStatus::SKIPPED)
        {
          halt();
          return NodeStatus::SKIPPED;
        }
        if(status == NodeStatus::SUCCESS)
        {
          halt();
          return NodeStatus::SUCCESS;
        }
        if(status == NodeStatus::RUNNING)
        {
          return NodeStatus::RUNNING;
        }
        if(retry_count_ < retries)
        {
          haltChild(0);
          current_ = 1;
          continue;
        }
        halt();
        return NodeStatus::FAILURE;
      }
      if(status == NodeStatus::RUNNING)
      {
        return NodeStatus::RUNNING;
      }
      if(status == NodeStatus::SUCCESS)
      {
        haltChild(1);
        retry_count_++;
        current_ = 0;
        continue;
      }
      halt();  // the recovery failed or was skipped
      return NodeStatus::FAILURE;
    }
    halt();
    return NodeStatus::FAILURE;
  }
  void halt() override
  {
    ControlNode::halt();
    retry_count_ = 0;
    current_ = 0;
  }

private:
  size_t current_ = 0;
  int retry_count_ = 0;
};

// Ticks every child from the first each tick, like a Sequence that re-ticks the children it already
// passed while a later one is RUNNING (Nav2's PipelineSequence).
class PipelineSequence : public BT::ControlNode
{
public:
  PipelineSequence(const std::string& name, const BT::NodeConfig& config) : BT::ControlNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    setStatus(NodeStatus::RUNNING);
    for(size_t i = 0; i < childrenCount(); i++)
    {
      const NodeStatus status = children_nodes_[i]->executeTick();
      if(status == NodeStatus::FAILURE)
      {
        haltChildren();
        last_running_ = 0;
        return NodeStatus::FAILURE;
      }
      if(status == NodeStatus::RUNNING && i >= last_running_)
      {
        last_running_ = i;
        return NodeStatus::RUNNING;
      }
    }
    haltChildren();
    last_running_ = 0;
    return NodeStatus::SUCCESS;
  }
  void halt() override
  {
    ControlNode::halt();
    last_running_ = 0;
  }

private:
  size_t last_running_ = 0;
};

// Ticks one child per activation, the next one each time; SUCCESS at the first success, FAILURE when
// every child failed in a row (Nav2's RoundRobin).
class RoundRobin : public BT::ControlNode
{
public:
  RoundRobin(const std::string& name, const BT::NodeConfig& config) : BT::ControlNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return {};
  }
  NodeStatus tick() override
  {
    const size_t count = childrenCount();
    setStatus(NodeStatus::RUNNING);
    size_t skipped = 0;
    while(failed_ + skipped < count)
    {
      const NodeStatus status = children_nodes_[current_]->executeTick();
      if(status != NodeStatus::RUNNING)
      {
        current_ = (current_ + 1) % count;
      }
      if(status == NodeStatus::SUCCESS)
      {
        failed_ = 0;
        haltChildren();
        return NodeStatus::SUCCESS;
      }
      if(status == NodeStatus::RUNNING)
      {
        return NodeStatus::RUNNING;
      }
      if(status == NodeStatus::FAILURE)
      {
        failed_++;
      }
      else
      {
        skipped++;
      }
    }
    haltChildren();
    failed_ = 0;
    return NodeStatus::FAILURE;
  }
  void halt() override
  {
    ControlNode::halt();
    failed_ = 0;
  }

private:
  size_t current_ = 0;
  size_t failed_ = 0;
};

// Ticks its child at its first tick, then again once `period` ticks have passed since the child's last
// success (Nav2's RateController counts seconds; the stand-in counts ticks); a RUNNING child is ticked
// every tick; RUNNING in between.
class RateController : public BT::DecoratorNode
{
public:
  RateController(const std::string& name, const BT::NodeConfig& config) : BT::DecoratorNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<int>("period", 3, "ticks between two runs of the child") };
  }
  NodeStatus tick() override
  {
    if(status() == NodeStatus::IDLE)
    {
      first_ = true;
      since_ = 0;
    }
    setStatus(NodeStatus::RUNNING);
    since_++;
    if(first_ || child_node_->status() == NodeStatus::RUNNING || since_ >= getInput<int>("period").value())
    {
      first_ = false;
      const NodeStatus status = child_node_->executeTick();
      if(status == NodeStatus::SUCCESS)
      {
        since_ = 0;
      }
      return status;
    }
    return NodeStatus::RUNNING;
  }

private:
  bool first_ = true;
  int since_ = 0;
};

// Copies `@goal_update` (when set) to `output_goal`, else `input_goal`, then ticks its child (Nav2's
// GoalUpdater).
class GoalUpdater : public BT::DecoratorNode
{
public:
  GoalUpdater(const std::string& name, const BT::NodeConfig& config) : BT::DecoratorNode(name, config)
  {}
  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("input_goal"), BT::OutputPort<std::string>("output_goal") };
  }
  NodeStatus tick() override
  {
    setStatus(NodeStatus::RUNNING);
    std::string goal = getInput<std::string>("input_goal").value();
    const std::string update = rootValue<std::string>(*this, "goal_update", "");
    if(!update.empty())
    {
      goal = update;
    }
    setOutput("output_goal", goal);
    const NodeStatus status = child_node_->executeTick();
    if(status != NodeStatus::RUNNING)
    {
      resetChild();
    }
    return status;
  }
};

inline void registerAll(BT::BehaviorTreeFactory& factory)
{
  factory.registerNodeType<SaySomething>("SaySomething");
  factory.registerNodeType<ThinkWhatToSay>("ThinkWhatToSay");
  factory.registerNodeType<CalculateGoal>("CalculateGoal");
  factory.registerNodeType<PrintTarget>("PrintTarget");
  factory.registerNodeType<BatteryOK>("BatteryOK");
  factory.registerNodeType<MoveBase>("MoveBase");
  factory.registerNodeType<IsDoorClosed>("IsDoorClosed");
  factory.registerNodeType<PassThroughDoor>("PassThroughDoor");
  factory.registerNodeType<OpenDoor>("OpenDoor");
  factory.registerNodeType<PickLock>("PickLock");
  factory.registerNodeType<SmashDoor>("SmashDoor");
  factory.registerNodeType<ComputePathToPose>("ComputePathToPose");
  factory.registerNodeType<FollowPath>("FollowPath");
  factory.registerNodeType<ClearEntireCostmap>("ClearEntireCostmap");
  factory.registerNodeType<GoalUpdated>("GoalUpdated");
  factory.registerNodeType<Spin>("Spin");
  factory.registerNodeType<Wait>("Wait");
  factory.registerNodeType<BackUp>("BackUp");
  factory.registerNodeType<RecoveryNode>("RecoveryNode");
  factory.registerNodeType<PipelineSequence>("PipelineSequence");
  factory.registerNodeType<RoundRobin>("RoundRobin");
  factory.registerNodeType<RateController>("RateController");
  factory.registerNodeType<GoalUpdater>("GoalUpdater");
  factory.registerScriptingEnum("DOCKED", 0);
  factory.registerScriptingEnum("NAVIGATING", 1);
  factory.registerScriptingEnum("RECOVERING", 2);
}
}  // namespace standins
