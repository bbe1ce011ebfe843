// bt_grasp's differential-test driver: load one tree file with BehaviorTree.CPP, tick it the way an
// application does (tickOnce() once per control period) and print what happened as one JSON object.
//
// Usage: btcpp_diff_driver TREE.xml [--max-ticks N] [--period-ms MS] [--rules RULES.json] [--models MODELS.json]
//                           [--set KEY=VALUE ...] [--nav2]
//
// --rules: BehaviorTree.CPP's substitution rules (factory.loadSubstitutionRuleFromJSON), as a user's test loads them.
// --models: node models to stand in for ([{"kind": "Action"|"Condition", "id", "ports": [{"name", "direction":
//   "input"|"output"|"inout", "type": "int"|"double"|"bool"|"string"|"any", "default": text|null}]}], made by
//   record.py from a TreeNodesModel): each is registered with those ports and a ModelStandIn, which succeeds and
//   writes every connected output port its type's default (0, 0.0, false, ""), as bt-grasp's model stand-ins do.
// --set: a root blackboard entry before the first tick (an integer if the text is one, else a real, else text).
// --nav2: register Nav2's RecoveryNode, PipelineSequence, RoundRobin and RateController (nav2_controls.hpp)
//   instead of the stand-ins of standins.hpp.
//
// Output: {"status", "ticks", "statuses": [root status per tickOnce], "runs": [root executions per
// tickOnce], "nodes": [statuses of every non-root node after each tickOnce, preorder, one letter each],
// "paths": [the nodes' full paths], "blackboard": {key: {"type": int|real|str|bool|empty|other, "value"}},
// "leaves": {name: {"ticks", "starts", "halts"}}, "transitions": [[tick, full path, previous, new status], ...]
// (every status change in order, as BT.CPP's StatusChangeLogger sees it: halts to IDLE included),
// "error": null | {"phase": "load"|"tick", "message"}}.
//
// The test leaves registered here have twins in tests/tree_conformance/leaves.py (Python), and the stand-ins
// of other projects' nodes (standins.hpp) in tests/tree_conformance/standins.py; keep them equal.
// This file is bt_grasp's own code; it only links against a BehaviorTree.CPP build the user provides.

#include <behaviortree_cpp/bt_factory.h>
#include <behaviortree_cpp/contrib/json.hpp>
#include <behaviortree_cpp/loggers/abstract_logger.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "nav2_controls.hpp"
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

// A node a TreeNodesModel declares and nothing registers (--models): SUCCESS, every connected output port
// written with its type's default, as bt-grasp's stand-ins from a model do (tests/tree_conformance/rules/).
struct ModelPort
{
  std::string name;
  std::string type;
};

template <class Base>
class ModelStandIn : public Base
{
public:
  ModelStandIn(const std::string& name, const BT::NodeConfig& config, std::vector<ModelPort> outputs)
    : Base(name, config), outputs_(std::move(outputs))
  {}

  BT::NodeStatus tick() override
  {
    traces()[this->name()].ticks++;
    for(const auto& port : outputs_)
    {
      if(port.type == "int")
        std::ignore = this->setOutput(port.name, 0);
      else if(port.type == "double")
        std::ignore = this->setOutput(port.name, 0.0);
      else if(port.type == "bool")
        std::ignore = this->setOutput(port.name, false);
      else if(port.type == "string")
        std::ignore = this->setOutput(port.name, std::string());
    }
    return BT::NodeStatus::SUCCESS;
  }

private:
  std::vector<ModelPort> outputs_;
};

template <typename T>
std::pair<std::string, BT::PortInfo> modelPort(BT::PortDirection direction, const std::string& name)
{
  return BT::CreatePort<T>(direction, name);
}

void registerModels(BT::BehaviorTreeFactory& factory, const std::string& path)
{
  std::ifstream file(path);
  const auto models = nlohmann::json::parse(file);
  for(const auto& model : models)
  {
    if(factory.builders().count(model.at("id").get<std::string>()) != 0)
    {
      continue;  // a node someone registered is that node, not a stand-in
    }
    BT::TreeNodeManifest manifest;
    const std::string kind = model.at("kind").get<std::string>();
    manifest.type = kind == "Condition" ? BT::NodeType::CONDITION : BT::NodeType::ACTION;
    manifest.registration_ID = model.at("id").get<std::string>();
    std::vector<ModelPort> outputs;
    for(const auto& port : model.at("ports"))
    {
      const std::string name = port.at("name").get<std::string>();
      const std::string type = port.at("type").get<std::string>();
      const std::string dir = port.at("direction").get<std::string>();
      const auto direction = dir == "input"  ? BT::PortDirection::INPUT :
                             dir == "output" ? BT::PortDirection::OUTPUT :
                                               BT::PortDirection::INOUT;
      std::pair<std::string, BT::PortInfo> info =
          type == "int"    ? modelPort<int>(direction, name) :
          type == "double" ? modelPort<double>(direction, name) :
          type == "bool"   ? modelPort<bool>(direction, name) :
          type == "string" ? modelPort<std::string>(direction, name) :
                             modelPort<BT::AnyTypeAllowed>(direction, name);
      if(port.contains("default") && !port.at("default").is_null())
      {
        info.second.setDefaultValue(port.at("default").get<std::string>());
      }
      manifest.ports.insert(info);
      if(direction != BT::PortDirection::INPUT)
      {
        outputs.push_back({ name, type });
      }
    }
    if(manifest.type == BT::NodeType::CONDITION)
    {
      factory.registerBuilder(manifest, [outputs](const std::string& name, const BT::NodeConfig& config) {
        return std::make_unique<ModelStandIn<BT::ConditionNode>>(name, config, outputs);
      });
    }
    else
    {
      factory.registerBuilder(manifest, [outputs](const std::string& name, const BT::NodeConfig& config) {
        return std::make_unique<ModelStandIn<BT::SyncActionNode>>(name, config, outputs);
      });
    }
  }
}

// Every status change of every node, in order, as a StatusChangeLogger (StdCoutLogger, Groot2's FileLogger2)
// receives it, with the control period it happened in.
class TransitionRecorder : public BT::StatusChangeLogger
{
public:
  TransitionRecorder(BT::TreeNode* root, const int* tick) : BT::StatusChangeLogger(root), tick_(tick)
  {}
  ~TransitionRecorder() override
  {
    unsubscribeFromTreeChanges();
  }
  TransitionRecorder(const TransitionRecorder&) = delete;
  TransitionRecorder& operator=(const TransitionRecorder&) = delete;
  TransitionRecorder(TransitionRecorder&&) = delete;
  TransitionRecorder& operator=(TransitionRecorder&&) = delete;

  void callback(BT::Duration, const BT::TreeNode& node, BT::NodeStatus prev, BT::NodeStatus status) override
  {
    entries.push_back({ *tick_, node.fullPath(), BT::toStr(prev), BT::toStr(status) });
  }
  void flush() override
  {}

  struct Entry
  {
    int tick;
    std::string path;
    std::string prev;
    std::string status;
  };
  std::vector<Entry> entries;

private:
  const int* tick_;
};

BT::Any literalValue(const std::string& text)
{
  char* end = nullptr;
  const long long integer = std::strtoll(text.c_str(), &end, 10);
  if(!text.empty() && end == text.c_str() + text.size())
    return BT::Any(static_cast<int64_t>(integer));
  const double real = std::strtod(text.c_str(), &end);
  if(!text.empty() && end == text.c_str() + text.size())
    return BT::Any(real);
  return BT::Any(text);
}

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
  std::string rules;
  std::string models;
  std::vector<std::string> sets;
  bool nav2 = false;
};

const char* const USAGE = "usage: btcpp_diff_driver TREE.xml [--max-ticks N] [--period-ms MS] [--rules RULES.json] "
                          "[--models MODELS.json] [--set KEY=VALUE ...] [--nav2]\n";

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
    else if(arg == "--rules" && i + 1 < argc)
      options.rules = argv[++i];
    else if(arg == "--models" && i + 1 < argc)
      options.models = argv[++i];
    else if(arg == "--set" && i + 1 < argc)
      options.sets.emplace_back(argv[++i]);
    else if(arg == "--nav2")
      options.nav2 = true;
    else if(options.path.empty())
      options.path = arg;
    else
    {
      std::cerr << USAGE;
      std::exit(2);
    }
  }
  if(options.path.empty())
  {
    std::cerr << USAGE;
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
  if(options.nav2)
    nav2::registerAll(factory);
  else
    standins::registerAll(factory);

  BT::Tree tree;
  try
  {
    if(!options.models.empty())
      registerModels(factory, options.models);
    if(!options.rules.empty())
    {
      std::ifstream file(options.rules);
      const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
      factory.loadSubstitutionRuleFromJSON(text);
    }
    tree = factory.createTreeFromFile(options.path);
    for(const auto& item : options.sets)
    {
      const auto eq = item.find('=');
      tree.rootBlackboard()->set(item.substr(0, eq), literalValue(item.substr(eq + 1)));
    }
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

  int ticks = 0;
  TransitionRecorder recorder(tree.rootNode(), &ticks);
  std::vector<std::string> statuses;
  std::vector<int> runs;
  std::vector<std::string> snapshots;
  BT::NodeStatus status = BT::NodeStatus::IDLE;
  std::string error_message;
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
  out << "}, \"transitions\": [";
  for(size_t i = 0; i < recorder.entries.size(); i++)
  {
    const auto& entry = recorder.entries[i];
    out << (i ? ", " : "") << "[" << entry.tick << ", " << jsonString(entry.path) << ", " << jsonString(entry.prev)
        << ", " << jsonString(entry.status) << "]";
  }
  out << "], \"error\": ";
  if(error_message.empty())
    out << "null";
  else
    out << "{\"phase\": \"tick\", \"message\": " << jsonString(error_message) << "}";
  out << "}\n";
  std::cout << out.str();
  return 0;
}
