// bt_grasp's differential-test driver: load one tree file with BehaviorTree.CPP, tick it the way an
// application does (tickOnce() once per control period) and print what happened as one JSON object.
//
// Usage: btcpp_diff_driver TREE.xml [--max-ticks N] [--period-ms MS]
//
// Output: {"status", "ticks", "statuses": [root status per tickOnce], "runs": [root executions per
// tickOnce], "nodes": [statuses of every non-root node after each tickOnce, preorder, one letter each],
// "paths": [the nodes' full paths], "blackboard": {key: {"type": int|real|str|bool|empty|other, "value"}},
// "leaves": {name: {"ticks", "starts", "halts"}}, "error": null | {"phase": "load"|"tick", "message"}}.
//
// The test leaves registered here have twins in tests/tree_conformance/leaves.py (Python), and the stand-ins
// of other projects' nodes (standins.hpp) in tests/tree_conformance/standins.py; keep them equal.
// This file is bt_grasp's own code; it only links against a BehaviorTree.CPP build the user provides.

#include <behaviortree_cpp/bt_factory.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "standins.hpp"

namespace
{
struct LeafTrace
{
  int ticks = 0;
  int starts = 0;
  int halts = 0;
};

std::map<std::string, LeafTrace>& traces()
{
  static std::map<std::string, LeafTrace> table;
  return table;
}

BT::NodeStatus parseStatus(const std::string& text)
{
  if(text == "SUCCESS")
    return BT::NodeStatus::SUCCESS;
  if(text == "FAILURE")
    return BT::NodeStatus::FAILURE;
  if(text == "SKIPPED")
    return BT::NodeStatus::SKIPPED;
  throw BT::RuntimeError("TestAction: result must be SUCCESS, FAILURE or SKIPPED, got ", text);
}

// RUNNING for `running` ticks after it starts, then `result`. Counts ticks, starts and halts.
class TestAction : public BT::ActionNodeBase
{
public:
  TestAction(const std::string& name, const BT::NodeConfig& config) : BT::ActionNodeBase(name, config)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("result", "SUCCESS", "final status"),
             BT::InputPort<int>("running", 0, "RUNNING ticks before the result") };
  }

  BT::NodeStatus tick() override
  {
    auto& trace = traces()[name()];
    trace.ticks++;
    if(status() == BT::NodeStatus::IDLE)
    {
      trace.starts++;
      done_ = 0;
    }
    const int running = getInput<int>("running").value();
    if(done_ < running)
    {
      done_++;
      return BT::NodeStatus::RUNNING;
    }
    return parseStatus(getInput<std::string>("result").value());
  }

  void halt() override
  {
    traces()[name()].halts++;
    done_ = 0;
    resetStatus();
  }

private:
  int done_ = 0;
};

// SUCCESS when the input port `value` reads true, FAILURE otherwise.
class TestCondition : public BT::ConditionNode
{
public:
  TestCondition(const std::string& name, const BT::NodeConfig& config) : BT::ConditionNode(name, config)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<bool>("value", "the condition") };
  }

  BT::NodeStatus tick() override
  {
    traces()[name()].ticks++;
    auto value = getInput<bool>("value");
    if(!value)
    {
      throw BT::RuntimeError(value.error());
    }
    return value.value() ? BT::NodeStatus::SUCCESS : BT::NodeStatus::FAILURE;
  }
};

// Reads the integer `value` (0 when the entry is empty), writes value + `step`; SUCCESS.
class Counter : public BT::SyncActionNode
{
public:
  Counter(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::BidirectionalPort<int>("value", "the counter"),
             BT::InputPort<int>("step", 1, "the increment") };
  }

  BT::NodeStatus tick() override
  {
    traces()[name()].ticks++;
    int current = 0;
    if(auto value = getInput<int>("value"))
    {
      current = value.value();
    }
    setOutput("value", current + getInput<int>("step").value());
    return BT::NodeStatus::SUCCESS;
  }
};

// Writes the real number `value` to the output port `out`; SUCCESS.
class WriteReal : public BT::SyncActionNode
{
public:
  WriteReal(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<double>("value", "the number"), BT::OutputPort<double>("out", "where") };
  }

  BT::NodeStatus tick() override
  {
    traces()[name()].ticks++;
    setOutput("out", getInput<double>("value").value());
    return BT::NodeStatus::SUCCESS;
  }
};

// Reads the text port `text` and copies it to the output `out`; SUCCESS.
class EchoText : public BT::SyncActionNode
{
public:
  EchoText(const std::string& name, const BT::NodeConfig& config) : BT::SyncActionNode(name, config)
  {}

  static BT::PortsList providedPorts()
  {
    return { BT::InputPort<std::string>("text", "the text"), BT::OutputPort<std::string>("out", "where") };
  }

  BT::NodeStatus tick() override
  {
    traces()[name()].ticks++;
    setOutput("out", getInput<std::string>("text").value());
    return BT::NodeStatus::SUCCESS;
  }
};

std::string jsonString(const std::string& text)
{
  std::ostringstream out;
  out << '"';
  for(const unsigned char c : text)
  {
    switch(c)
    {
      case '"':
        out << "\\\"";
        break;
      case '\\':
        out << "\\\\";
        break;
      case '\n':
        out << "\\n";
        break;
      case '\t':
        out << "\\t";
        break;
      default:
        if(c < 0x20)
        {
          char buffer[8];
          std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
          out << buffer;
        }
        else
        {
          out << c;
        }
    }
  }
  out << '"';
  return out.str();
}

std::string jsonReal(double value)
{
  if(std::isnan(value))
    return "\"nan\"";
  if(std::isinf(value))
    return value > 0 ? "\"inf\"" : "\"-inf\"";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

std::string jsonValue(const BT::Any& value)
{
  if(value.empty())
    return "{\"type\": \"empty\"}";
  if(value.isType<bool>())
    return std::string("{\"type\": \"bool\", \"value\": ") + (value.cast<bool>() ? "true" : "false") + "}";
  if(value.isString())
    return "{\"type\": \"str\", \"value\": " + jsonString(value.cast<std::string>()) + "}";
  if(value.castedType() == typeid(int64_t))
    return "{\"type\": \"int\", \"value\": " + std::to_string(value.cast<int64_t>()) + "}";
  if(value.castedType() == typeid(uint64_t))
    return "{\"type\": \"int\", \"value\": " + std::to_string(value.cast<uint64_t>()) + "}";
  if(value.castedType() == typeid(double))
    return "{\"type\": \"real\", \"value\": " + jsonReal(value.cast<double>()) + "}";
  return "{\"type\": \"other\", \"value\": " + jsonString(BT::demangle(value.type())) + "}";
}

char statusLetter(BT::NodeStatus status)
{
  switch(status)
  {
    case BT::NodeStatus::IDLE:
      return 'I';
    case BT::NodeStatus::RUNNING:
      return 'R';
    case BT::NodeStatus::SUCCESS:
      return 'S';
    case BT::NodeStatus::FAILURE:
      return 'F';
    case BT::NodeStatus::SKIPPED:
      return 'K';
  }
  return '?';
}

void preorder(BT::TreeNode* node, std::vector<BT::TreeNode*>& out)
{
  out.push_back(node);
  if(auto* control = dynamic_cast<BT::ControlNode*>(node))
  {
    for(auto* child : control->children())
      preorder(child, out);
  }
  else if(auto* decorator = dynamic_cast<BT::DecoratorNode*>(node))
  {
    if(decorator->child() != nullptr)
      preorder(decorator->child(), out);
  }
}

struct Options
{
  std::string path;
  int max_ticks = 20;
  int period_ms = 0;
};

Options parseArgs(int argc, char** argv)
{
  Options options;
  for(int i = 1; i < argc; i++)
  {
    const std::string arg = argv[i];
    if(arg == "--max-ticks" && i + 1 < argc)
      options.max_ticks = std::atoi(argv[++i]);
    else if(arg == "--period-ms" && i + 1 < argc)
      options.period_ms = std::atoi(argv[++i]);
    else if(options.path.empty())
      options.path = arg;
    else
    {
      std::cerr << "usage: btcpp_diff_driver TREE.xml [--max-ticks N] [--period-ms MS]\n";
      std::exit(2);
    }
  }
  if(options.path.empty())
  {
    std::cerr << "usage: btcpp_diff_driver TREE.xml [--max-ticks N] [--period-ms MS]\n";
    std::exit(2);
  }
  return options;
}

void printError(const std::string& phase, const std::string& message)
{
  std::cout << "{\"status\": \"ERROR\", \"error\": {\"phase\": " << jsonString(phase)
            << ", \"message\": " << jsonString(message) << "}}\n";
}
}  // namespace

int main(int argc, char** argv)
{
  const Options options = parseArgs(argc, argv);
  BT::BehaviorTreeFactory factory;
  factory.registerNodeType<TestAction>("TestAction");
  factory.registerNodeType<TestCondition>("TestCondition");
  factory.registerNodeType<Counter>("Counter");
  factory.registerNodeType<WriteReal>("WriteReal");
  factory.registerNodeType<EchoText>("EchoText");
  factory.registerScriptingEnum("RED", 1);
  factory.registerScriptingEnum("GREEN", 2);
  factory.registerScriptingEnum("BLUE", 3);
  standins::registerAll(factory);

  BT::Tree tree;
  try
  {
    tree = factory.createTreeFromFile(options.path);
  }
  catch(const std::exception& err)
  {
    printError("load", err.what());
    return 0;
  }

  std::vector<BT::TreeNode*> nodes;
  preorder(tree.rootNode(), nodes);
  int executions = 0;
  tree.rootNode()->setTickMonitorCallback(
      [&executions](BT::TreeNode&, BT::NodeStatus, std::chrono::microseconds) { executions++; });

  std::vector<std::string> statuses;
  std::vector<int> runs;
  std::vector<std::string> snapshots;
  BT::NodeStatus status = BT::NodeStatus::IDLE;
  std::string error_message;
  int ticks = 0;
  try
  {
    while(ticks < options.max_ticks)
    {
      ticks++;
      executions = 0;
      status = tree.tickOnce();
      statuses.push_back(BT::toStr(status));
      runs.push_back(executions);
      std::string snapshot;
      for(size_t i = 1; i < nodes.size(); i++)
        snapshot.push_back(statusLetter(nodes[i]->status()));
      snapshots.push_back(snapshot);
      if(BT::isStatusCompleted(status))
        break;
      if(options.period_ms > 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(options.period_ms));
    }
  }
  catch(const std::exception& err)
  {
    error_message = err.what();
  }

  std::ostringstream out;
  out << "{\"status\": " << jsonString(error_message.empty() ? BT::toStr(status) : "ERROR");
  out << ", \"ticks\": " << ticks << ", \"statuses\": [";
  for(size_t i = 0; i < statuses.size(); i++)
    out << (i ? ", " : "") << jsonString(statuses[i]);
  out << "], \"runs\": [";
  for(size_t i = 0; i < runs.size(); i++)
    out << (i ? ", " : "") << runs[i];
  out << "], \"nodes\": [";
  for(size_t i = 0; i < snapshots.size(); i++)
    out << (i ? ", " : "") << jsonString(snapshots[i]);
  out << "], \"paths\": [";
  for(size_t i = 1; i < nodes.size(); i++)
    out << (i > 1 ? ", " : "") << jsonString(nodes[i]->fullPath());
  out << "], \"blackboard\": {";
  auto blackboard = tree.rootBlackboard();
  std::vector<std::string> keys;
  for(const auto& key : blackboard->getKeys())
    keys.emplace_back(key);
  std::sort(keys.begin(), keys.end());
  for(size_t i = 0; i < keys.size(); i++)
  {
    auto entry = blackboard->getEntry(keys[i]);
    out << (i ? ", " : "") << jsonString(keys[i]) << ": " << jsonValue(entry->value);
  }
  out << "}, \"leaves\": {";
  bool first = true;
  for(const auto& [name, trace] : traces())
  {
    out << (first ? "" : ", ") << jsonString(name) << ": {\"ticks\": " << trace.ticks
        << ", \"starts\": " << trace.starts << ", \"halts\": " << trace.halts << "}";
    first = false;
  }
  out << "}, \"error\": ";
  if(error_message.empty())
    out << "null";
  else
    out << "{\"phase\": \"tick\", \"message\": " << jsonString(error_message) << "}";
  out << "}\n";
  std::cout << out.str();
  return 0;
}
