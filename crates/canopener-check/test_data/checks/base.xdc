<?xml version="1.0" encoding="utf-8"?>
<ISO15745ProfileContainer xmlns:xsd="http://www.w3.org/2001/XMLSchema" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xmlns="http://www.canopen.org/xml/1.1">
  <ISO15745Profile>
    <ProfileHeader xmlns="">
      <ProfileIdentification>CANopen device profile</ProfileIdentification>
      <ProfileRevision>1.1</ProfileRevision>
      <ProfileName />
      <ProfileSource />
      <ProfileClassID>Device</ProfileClassID>
      <ISO15745Reference>
        <ISO15745Part>1</ISO15745Part>
        <ISO15745Edition>1</ISO15745Edition>
        <ProfileTechnology>CANopen</ProfileTechnology>
      </ISO15745Reference>
    </ProfileHeader>
    <ProfileBody xmlns:q1="http://www.canopen.org/xml/1.1" xsi:type="q1:ProfileBody_Device_CANopen" formatName="CANopen" formatVersion="1.0" fileName="base.xdc" fileCreator="canopener developers" fileCreationDate="2026-05-15" fileCreationTime="09:45:00" fileModifiedBy="canopener developers" fileModificationDate="2026-06-01" fileModificationTime="14:30:00" fileVersion="1" supportedLanguages="en" xmlns="">
      <q1:DeviceIdentity>
        <q1:vendorName>canopener</q1:vendorName>
        <q1:vendorID>0x00000ABC</q1:vendorID>
        <q1:productName>Fixture IO 8/8</q1:productName>
        <q1:productID>0x00000401</q1:productID>
        <q1:productText>
          <description lang="en">Checker fixture: 8 digital inputs, 8 digital outputs</description>
        </q1:productText>
        <q1:orderNumber>FIX-IO-88</q1:orderNumber>
      </q1:DeviceIdentity>
      <q1:DeviceFunction>
        <q1:capabilities>
          <q1:characteristicsList>
            <q1:characteristic>
              <q1:characteristicName>
                <label lang="en">SW library</label>
              </q1:characteristicName>
              <q1:characteristicContent>
                <label lang="en">canopener</label>
              </q1:characteristicContent>
            </q1:characteristic>
          </q1:characteristicsList>
        </q1:capabilities>
      </q1:DeviceFunction>
      <q1:ApplicationProcess>
        <q1:dataTypeList>
          <q1:struct name="Identity object" uniqueID="UID_REC_1018">
            <q1:varDeclaration name="Highest sub-index supported" uniqueID="UID_RECSUB_101800">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Vendor-ID" uniqueID="UID_RECSUB_101801">
              <UDINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Product code" uniqueID="UID_RECSUB_101802">
              <UDINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Revision number" uniqueID="UID_RECSUB_101803">
              <UDINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Serial number" uniqueID="UID_RECSUB_101804">
              <UDINT />
            </q1:varDeclaration>
          </q1:struct>
          <q1:struct name="SDO server parameter" uniqueID="UID_REC_1200">
            <q1:varDeclaration name="Highest sub-index supported" uniqueID="UID_RECSUB_120000">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="COB-ID client to server" uniqueID="UID_RECSUB_120001">
              <UDINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="COB-ID server to client" uniqueID="UID_RECSUB_120002">
              <UDINT />
            </q1:varDeclaration>
          </q1:struct>
          <q1:struct name="RPDO communication parameter" uniqueID="UID_REC_1400">
            <q1:varDeclaration name="Highest sub-index supported" uniqueID="UID_RECSUB_140000">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="COB-ID used by RPDO" uniqueID="UID_RECSUB_140001">
              <UDINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Transmission type" uniqueID="UID_RECSUB_140002">
              <USINT />
            </q1:varDeclaration>
          </q1:struct>
          <q1:struct name="RPDO mapping parameter" uniqueID="UID_REC_1600">
            <q1:varDeclaration name="Number of mapped objects" uniqueID="UID_RECSUB_160000">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Mapping entry 1" uniqueID="UID_RECSUB_160001">
              <UDINT />
            </q1:varDeclaration>
          </q1:struct>
          <q1:struct name="TPDO communication parameter" uniqueID="UID_REC_1800">
            <q1:varDeclaration name="Highest sub-index supported" uniqueID="UID_RECSUB_180000">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="COB-ID used by TPDO" uniqueID="UID_RECSUB_180001">
              <UDINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Transmission type" uniqueID="UID_RECSUB_180002">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Inhibit time" uniqueID="UID_RECSUB_180003">
              <UINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Event timer" uniqueID="UID_RECSUB_180005">
              <UINT />
            </q1:varDeclaration>
          </q1:struct>
          <q1:struct name="TPDO mapping parameter" uniqueID="UID_REC_1A00">
            <q1:varDeclaration name="Number of mapped objects" uniqueID="UID_RECSUB_1A0000">
              <USINT />
            </q1:varDeclaration>
            <q1:varDeclaration name="Mapping entry 1" uniqueID="UID_RECSUB_1A0001">
              <UDINT />
            </q1:varDeclaration>
          </q1:struct>
          <q1:array name="Read input 8-bit" uniqueID="UID_ARR_6000">
            <q1:subrange lowerLimit="0" upperLimit="1" />
            <USINT />
          </q1:array>
          <q1:array name="Write output 8-bit" uniqueID="UID_ARR_6200">
            <q1:subrange lowerLimit="0" upperLimit="1" />
            <USINT />
          </q1:array>
        </q1:dataTypeList>
        <q1:parameterList>
          <q1:parameter uniqueID="UID_OBJ_1000" access="read">
            <label lang="en">Device type</label>
            <UDINT />
            <q1:actualValue value="0x000F0191" />
            <q1:defaultValue value="0x000F0191" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1001" access="read">
            <label lang="en">Error register</label>
            <USINT />
            <q1:actualValue value="0" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1017" access="readWrite">
            <label lang="en">Producer heartbeat time</label>
            <UINT />
            <q1:actualValue value="1000" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1018">
            <label lang="en">Identity object</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_REC_1018" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_101800" access="read">
            <label lang="en">Highest sub-index supported</label>
            <USINT />
            <q1:actualValue value="4" />
            <q1:defaultValue value="4" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_101801" access="read">
            <label lang="en">Vendor-ID</label>
            <UDINT />
            <q1:actualValue value="0x00000ABC" />
            <q1:defaultValue value="0x00000ABC" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_101802" access="read">
            <label lang="en">Product code</label>
            <UDINT />
            <q1:actualValue value="0x00000401" />
            <q1:defaultValue value="0x00000401" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_101803" access="read">
            <label lang="en">Revision number</label>
            <UDINT />
            <q1:actualValue value="0x00010002" />
            <q1:defaultValue value="0x00010002" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_101804" access="read">
            <label lang="en">Serial number</label>
            <UDINT />
            <q1:actualValue value="0" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1200">
            <label lang="en">SDO server parameter</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_REC_1200" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_120000" access="read">
            <label lang="en">Highest sub-index supported</label>
            <USINT />
            <q1:actualValue value="2" />
            <q1:defaultValue value="2" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_120001" access="read">
            <label lang="en">COB-ID client to server</label>
            <UDINT />
            <q1:actualValue value="0x605" />
            <q1:defaultValue value="$NODEID+0x600" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_120002" access="read">
            <label lang="en">COB-ID server to client</label>
            <UDINT />
            <q1:actualValue value="0x585" />
            <q1:defaultValue value="$NODEID+0x580" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1400">
            <label lang="en">RPDO communication parameter</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_REC_1400" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_140000" access="read">
            <label lang="en">Highest sub-index supported</label>
            <USINT />
            <q1:actualValue value="2" />
            <q1:defaultValue value="2" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_140001" access="readWrite">
            <label lang="en">COB-ID used by RPDO</label>
            <UDINT />
            <q1:actualValue value="0x205" />
            <q1:defaultValue value="$NODEID+0x200" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_140002" access="readWrite">
            <label lang="en">Transmission type</label>
            <USINT />
            <q1:actualValue value="255" />
            <q1:defaultValue value="255" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1600">
            <label lang="en">RPDO mapping parameter</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_REC_1600" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_160000" access="readWrite">
            <label lang="en">Number of mapped objects</label>
            <USINT />
            <q1:actualValue value="1" />
            <q1:defaultValue value="1" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_160001" access="readWrite">
            <label lang="en">Mapping entry 1</label>
            <UDINT />
            <q1:actualValue value="0x62000108" />
            <q1:defaultValue value="0x62000108" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1800">
            <label lang="en">TPDO communication parameter</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_REC_1800" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_180000" access="read">
            <label lang="en">Highest sub-index supported</label>
            <USINT />
            <q1:actualValue value="5" />
            <q1:defaultValue value="5" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_180001" access="readWrite">
            <label lang="en">COB-ID used by TPDO</label>
            <UDINT />
            <q1:actualValue value="0x185" />
            <q1:defaultValue value="$NODEID+0x180" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_180002" access="readWrite">
            <label lang="en">Transmission type</label>
            <USINT />
            <q1:actualValue value="255" />
            <q1:defaultValue value="255" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_180003" access="readWrite">
            <label lang="en">Inhibit time</label>
            <UINT />
            <q1:actualValue value="0" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_180005" access="readWrite">
            <label lang="en">Event timer</label>
            <UINT />
            <q1:actualValue value="100" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_1A00">
            <label lang="en">TPDO mapping parameter</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_REC_1A00" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_1A0000" access="readWrite">
            <label lang="en">Number of mapped objects</label>
            <USINT />
            <q1:actualValue value="1" />
            <q1:defaultValue value="1" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_1A0001" access="readWrite">
            <label lang="en">Mapping entry 1</label>
            <UDINT />
            <q1:actualValue value="0x60000108" />
            <q1:defaultValue value="0x60000108" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_2000" access="readWrite">
            <label lang="en">Input filter time</label>
            <UINT />
            <q1:actualValue value="20" />
            <q1:defaultValue value="10" />
            <q1:allowedValues>
              <q1:range>
                <minValue value="1" />
                <maxValue value="1000" />
              </q1:range>
            </q1:allowedValues>
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_6000">
            <label lang="en">Read input 8-bit</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_ARR_6000" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_600000" access="read">
            <label lang="en">Number of input 8-bit</label>
            <USINT />
            <q1:actualValue value="1" />
            <q1:defaultValue value="1" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_600001" access="read">
            <label lang="en">Read input 1h to 8h</label>
            <USINT />
            <q1:denotation>
              <label lang="en">Door contacts</label>
            </q1:denotation>
            <q1:actualValue value="0" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_OBJ_6200">
            <label lang="en">Write output 8-bit</label>
            <q1:dataTypeIDRef uniqueIDRef="UID_ARR_6200" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_620000" access="read">
            <label lang="en">Number of output 8-bit</label>
            <USINT />
            <q1:actualValue value="1" />
            <q1:defaultValue value="1" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_SUB_620001" access="readWriteOutput">
            <label lang="en">Write output 1h to 8h</label>
            <USINT />
            <q1:denotation>
              <label lang="en">Signal lamps</label>
            </q1:denotation>
            <q1:actualValue value="0" />
            <q1:defaultValue value="0" />
          </q1:parameter>
          <q1:parameter uniqueID="UID_CANOPENER_EDS">
            <label lang="en">EDS content without a CiA 311 element (canopener side channel)</label>
            <BITSTRING />
            <q1:property name="EDS:version" value="1" />
            <q1:property name="EDS:set" value="FileInfo:FileRevision=2" />
            <q1:property name="EDS:set" value="FileInfo:LastEDS=base.eds" />
            <q1:property name="EDS:set" value="DeviceInfo:RevisionNumber=0x00010002" />
            <q1:property name="EDS:set" value="DeviceComissioning:LSS_SerialNumber=0" />
            <q1:property name="EDS:section" value="Comments" />
            <q1:property name="EDS:entry" value="Lines=1" />
            <q1:property name="EDS:entry" value="Line1=Fixture for canopener's checker tests." />
          </q1:parameter>
        </q1:parameterList>
      </q1:ApplicationProcess>
    </ProfileBody>
  </ISO15745Profile>
  <ISO15745Profile>
    <ProfileHeader xmlns="">
      <ProfileIdentification>CANopen communication network profile</ProfileIdentification>
      <ProfileRevision>1.1</ProfileRevision>
      <ProfileName />
      <ProfileSource />
      <ProfileClassID>CommunicationNetwork</ProfileClassID>
      <ISO15745Reference>
        <ISO15745Part>1</ISO15745Part>
        <ISO15745Edition>1</ISO15745Edition>
        <ProfileTechnology>CANopen</ProfileTechnology>
      </ISO15745Reference>
    </ProfileHeader>
    <ProfileBody xmlns:q2="http://www.canopen.org/xml/1.1" xsi:type="q2:ProfileBody_CommunicationNetwork_CANopen" formatName="CANopen" formatVersion="1.0" fileName="base.xdc" fileCreator="canopener developers" fileCreationDate="2026-05-15" fileCreationTime="09:45:00" fileModifiedBy="canopener developers" fileModificationDate="2026-06-01" fileModificationTime="14:30:00" fileVersion="1" supportedLanguages="en" xmlns="">
      <ApplicationLayers>
        <q2:CANopenObjectList>
          <CANopenObject index="1000" name="Device type" objectType="7" PDOmapping="no" uniqueIDRef="UID_OBJ_1000" />
          <CANopenObject index="1001" name="Error register" objectType="7" PDOmapping="TPDO" uniqueIDRef="UID_OBJ_1001" />
          <CANopenObject index="1017" name="Producer heartbeat time" objectType="7" PDOmapping="no" uniqueIDRef="UID_OBJ_1017" />
          <CANopenObject index="1018" name="Identity object" objectType="9" uniqueIDRef="UID_OBJ_1018" subNumber="5">
            <CANopenSubObject subIndex="00" name="Highest sub-index supported" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_101800" />
            <CANopenSubObject subIndex="01" name="Vendor-ID" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_101801" />
            <CANopenSubObject subIndex="02" name="Product code" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_101802" />
            <CANopenSubObject subIndex="03" name="Revision number" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_101803" />
            <CANopenSubObject subIndex="04" name="Serial number" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_101804" />
          </CANopenObject>
          <CANopenObject index="1200" name="SDO server parameter" objectType="9" uniqueIDRef="UID_OBJ_1200" subNumber="3">
            <CANopenSubObject subIndex="00" name="Highest sub-index supported" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_120000" />
            <CANopenSubObject subIndex="01" name="COB-ID client to server" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_120001" />
            <CANopenSubObject subIndex="02" name="COB-ID server to client" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_120002" />
          </CANopenObject>
          <CANopenObject index="1400" name="RPDO communication parameter" objectType="9" uniqueIDRef="UID_OBJ_1400" subNumber="3">
            <CANopenSubObject subIndex="00" name="Highest sub-index supported" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_140000" />
            <CANopenSubObject subIndex="01" name="COB-ID used by RPDO" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_140001" />
            <CANopenSubObject subIndex="02" name="Transmission type" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_140002" />
          </CANopenObject>
          <CANopenObject index="1600" name="RPDO mapping parameter" objectType="9" uniqueIDRef="UID_OBJ_1600" subNumber="2">
            <CANopenSubObject subIndex="00" name="Number of mapped objects" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_160000" />
            <CANopenSubObject subIndex="01" name="Mapping entry 1" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_160001" />
          </CANopenObject>
          <CANopenObject index="1800" name="TPDO communication parameter" objectType="9" uniqueIDRef="UID_OBJ_1800" subNumber="5">
            <CANopenSubObject subIndex="00" name="Highest sub-index supported" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_180000" />
            <CANopenSubObject subIndex="01" name="COB-ID used by TPDO" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_180001" />
            <CANopenSubObject subIndex="02" name="Transmission type" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_180002" />
            <CANopenSubObject subIndex="03" name="Inhibit time" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_180003" />
            <CANopenSubObject subIndex="05" name="Event timer" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_180005" />
          </CANopenObject>
          <CANopenObject index="1A00" name="TPDO mapping parameter" objectType="9" uniqueIDRef="UID_OBJ_1A00" subNumber="2">
            <CANopenSubObject subIndex="00" name="Number of mapped objects" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_1A0000" />
            <CANopenSubObject subIndex="01" name="Mapping entry 1" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_1A0001" />
          </CANopenObject>
          <CANopenObject index="2000" name="Input filter time" objectType="7" PDOmapping="no" uniqueIDRef="UID_OBJ_2000" />
          <CANopenObject index="6000" name="Read input 8-bit" objectType="8" uniqueIDRef="UID_OBJ_6000" subNumber="2">
            <CANopenSubObject subIndex="00" name="Number of input 8-bit" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_600000" />
            <CANopenSubObject subIndex="01" name="Read input 1h to 8h" objectType="7" PDOmapping="TPDO" uniqueIDRef="UID_SUB_600001" />
          </CANopenObject>
          <CANopenObject index="6200" name="Write output 8-bit" objectType="8" uniqueIDRef="UID_OBJ_6200" subNumber="2">
            <CANopenSubObject subIndex="00" name="Number of output 8-bit" objectType="7" PDOmapping="no" uniqueIDRef="UID_SUB_620000" />
            <CANopenSubObject subIndex="01" name="Write output 1h to 8h" objectType="7" PDOmapping="RPDO" uniqueIDRef="UID_SUB_620001" />
          </CANopenObject>
        </q2:CANopenObjectList>
        <dummyUsage>
          <dummy entry="Dummy0001=0" />
          <dummy entry="Dummy0002=1" />
          <dummy entry="Dummy0003=1" />
          <dummy entry="Dummy0004=1" />
          <dummy entry="Dummy0005=1" />
          <dummy entry="Dummy0006=1" />
          <dummy entry="Dummy0007=1" />
        </dummyUsage>
      </ApplicationLayers>
      <TransportLayers>
        <PhysicalLayer>
          <baudRate>
            <supportedBaudRate value="50 Kbps" />
            <supportedBaudRate value="125 Kbps" />
            <supportedBaudRate value="250 Kbps" />
            <supportedBaudRate value="500 Kbps" />
            <supportedBaudRate value="1000 Kbps" />
          </baudRate>
        </PhysicalLayer>
      </TransportLayers>
      <NetworkManagement>
        <CANopenGeneralFeatures granularity="8" nrOfRxPDO="1" nrOfTxPDO="1" bootUpSlave="true" layerSettingServiceSlave="true" />
        <CANopenMasterFeatures />
        <deviceCommissioning nodeID="5" nodeName="Door panel IO" actualBaudRate="250 Kbps" networkNumber="1" networkName="Machine network" CANopenManager="false" />
      </NetworkManagement>
    </ProfileBody>
  </ISO15745Profile>
</ISO15745ProfileContainer>
