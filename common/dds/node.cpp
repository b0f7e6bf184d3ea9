#include "dds/node.hpp"

#include <chrono>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/dds/topic/qos/TopicQos.hpp>

#include "dds/participant.hpp"

namespace shapeform::dds {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace detail {

Entities::~Entities() {
  // delete_contained_entities removes endpoints, publisher, subscriber and topics (children before
  // parents), then the participant goes and announces its departure.
  delete_participant(participant);
}

void delete_writer(Entities& e, fdds::DataWriter* w) noexcept {
  if (e.publisher != nullptr && w != nullptr) e.publisher->delete_datawriter(w);
}

void delete_reader(Entities& e, fdds::DataReader* r) noexcept {
  if (e.subscriber != nullptr && r != nullptr) {
    r->set_listener(nullptr);
    e.subscriber->delete_datareader(r);
  }
}

bool is_ok(const ReturnCode_t& rc) { return rc == ReturnCode_t::RETCODE_OK; }

SourceId source_of(const fdds::InstanceHandle_t& writer) {
  const auto guid = eprosima::fastrtps::rtps::iHandle2GUID(writer);
  SourceId s;
  std::copy(std::begin(guid.guidPrefix.value), std::end(guid.guidPrefix.value), s.prefix.begin());
  return s;
}

}  // namespace detail

namespace {

template <class Msg>
void register_type(fdds::DomainParticipant* p, const std::string& node) {
  fdds::TypeSupport type(new typename MsgTraits<Msg>::PubSubType());
  if (!detail::is_ok(type.register_type(p))) {
    throw std::runtime_error("register_type failed for " + type.get_type_name() + " (node " + node + ")");
  }
  const char* expected = type_name(MsgTraits<Msg>::topic);
  if (type.get_type_name() != expected) {
    throw std::logic_error("dds: generated type name " + type.get_type_name() +
                           " differs from the topic table's " + expected);
  }
}

}  // namespace

Node::Node(const TransportConfig& cfg, const std::string& name)
    : entities_(std::make_shared<detail::Entities>()) {
  // Any throw below destroys entities_, which deletes whatever was created so far.
  entities_->name = name;
  entities_->transport = cfg;
  entities_->participant = create_participant(cfg, name);

  register_type<msg::AgentState>(entities_->participant, name);
  register_type<msg::ShapeCommand>(entities_->participant, name);
  register_type<msg::TrackingTarget>(entities_->participant, name);
  register_type<msg::SwarmMetrics>(entities_->participant, name);
  register_type<msg::AgentStatus>(entities_->participant, name);

  // Constructed QoS (not *_QOS_DEFAULT, which XML profiles could change).
  entities_->publisher = entities_->participant->create_publisher(fdds::PublisherQos());
  if (entities_->publisher == nullptr) throw std::runtime_error("create_publisher failed (node " + name + ")");
  entities_->subscriber = entities_->participant->create_subscriber(fdds::SubscriberQos());
  if (entities_->subscriber == nullptr) {
    throw std::runtime_error("create_subscriber failed (node " + name + ")");
  }
}

SourceId Node::source() const {
  SourceId s;
  const auto& prefix = entities_->participant->guid().guidPrefix.value;
  std::copy(std::begin(prefix), std::end(prefix), s.prefix.begin());
  return s;
}

Node::~Node() = default;  // entities_ (the last owner) deletes everything; handles only hold weak_ptrs

void Node::check_type(TopicId requested, TopicId of_type) {
  if (requested != of_type) {
    throw std::logic_error(std::string("dds: topic ") + topic_name(requested) + " carries " +
                           type_name(requested) + ", not " + type_name(of_type));
  }
}

fdds::Topic* Node::topic(TopicId id) {
  auto& slot = entities_->topics[static_cast<std::size_t>(id)];
  if (slot == nullptr) {
    slot = entities_->participant->create_topic(topic_name(id), type_name(id), fdds::TopicQos());
    if (slot == nullptr) {
      throw std::runtime_error(std::string("create_topic failed for topic ") + topic_name(id) + " (node " +
                               entities_->name + ")");
    }
  }
  return slot;
}

fdds::DataWriter* Node::create_writer(TopicId id) {
  fdds::DataWriter* w = entities_->publisher->create_datawriter(topic(id), writer_qos(id));
  if (w == nullptr) {
    throw std::runtime_error(std::string("create_datawriter failed for topic ") + topic_name(id) +
                             " (node " + entities_->name + ")");
  }
  return w;
}

fdds::DataReader* Node::create_reader(TopicId id, fdds::DataReaderListener* listener) {
  fdds::DataReader* r = entities_->subscriber->create_datareader(topic(id), reader_qos(id, entities_->transport), listener,
                                                                 fdds::StatusMask::data_available() <<
                                                                     fdds::StatusMask::subscription_matched());
  if (r == nullptr) {
    throw std::runtime_error(std::string("create_datareader failed for topic ") + topic_name(id) +
                             " (node " + entities_->name + ")");
  }
  return r;
}

}  // namespace shapeform::dds
