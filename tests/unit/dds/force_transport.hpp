#pragma once
// For the DDS unit tests, which create several participants in one test process.
#include <fastrtps/xmlparser/XMLProfileManager.h>

namespace shapeform::test {

/// Fast DDS short-cuts endpoints of one process (intraprocess delivery). Switch that off so the tests
/// really go through the transport the profile builds (loopback UDP, and a secured participant's filter).
inline void force_transport() {
  eprosima::fastrtps::LibrarySettingsAttributes settings;
  settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
}

}  // namespace shapeform::test
