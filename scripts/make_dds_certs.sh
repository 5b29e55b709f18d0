#!/usr/bin/env bash
# Generates TEST certificates and signed DDS Security documents (never for deployment):
#   scripts/make_dds_certs.sh OUT_DIR [DOMAIN_ID]
# OUT_DIR gets: ca.pem/ca_key.pem (identity and permissions CA), drone.pem/drone_key.pem,
# rsu.pem/rsu_key.pem, governance.xml/.p7s (authentication + encryption required) and
# permissions.xml/.p7s granting both subjects the vp/* topics in the given domain.
set -euo pipefail
out="${1:?usage: make_dds_certs.sh OUT_DIR [DOMAIN_ID]}"
domain="${2:-0}"
mkdir -p "$out"
cd "$out"
subj="/C=US/O=vehicle_perception test"
openssl req -x509 -newkey rsa:2048 -nodes -keyout ca_key.pem -out ca.pem -days 3650 \
  -subj "$subj/CN=VP Test CA" 2>/dev/null
for who in drone rsu; do
  openssl req -newkey rsa:2048 -nodes -keyout "${who}_key.pem" -out "$who.csr" \
    -subj "$subj/CN=$who" 2>/dev/null
  openssl x509 -req -in "$who.csr" -CA ca.pem -CAkey ca_key.pem -CAcreateserial \
    -out "$who.pem" -days 3650 2>/dev/null
  rm -f "$who.csr"
done
cat > governance.xml <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules><domain_rule>
    <domains><id>$domain</id></domains>
    <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
    <enable_join_access_control>true</enable_join_access_control>
    <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
    <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
    <rtps_protection_kind>NONE</rtps_protection_kind>
    <topic_access_rules><topic_rule>
      <topic_expression>*</topic_expression>
      <enable_discovery_protection>true</enable_discovery_protection>
      <enable_liveliness_protection>true</enable_liveliness_protection>
      <enable_read_access_control>true</enable_read_access_control>
      <enable_write_access_control>true</enable_write_access_control>
      <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
      <data_protection_kind>ENCRYPT</data_protection_kind>
    </topic_rule></topic_access_rules>
  </domain_rule></domain_access_rules>
</dds>
XML
{
  echo '<?xml version="1.0" encoding="UTF-8"?>'
  echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd"><permissions>'
  for who in drone rsu; do
    subject=$(openssl x509 -in "$who.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')
    cat <<XML
  <grant name="${who}_grant"><subject_name>$subject</subject_name>
    <validity><not_before>2020-01-01T00:00:00</not_before><not_after>2035-01-01T00:00:00</not_after></validity>
    <allow_rule><domains><id>$domain</id></domains>
      <publish><topics><topic>*</topic></topics><partitions><partition>*</partition></partitions></publish>
      <subscribe><topics><topic>*</topic></topics><partitions><partition>*</partition></partitions></subscribe>
    </allow_rule><default>DENY</default></grant>
XML
  done
  echo '</permissions></dds>'
} > permissions.xml
for doc in governance permissions; do
  openssl smime -sign -in "$doc.xml" -text -out "$doc.p7s" -signer ca.pem -inkey ca_key.pem
done
echo "make_dds_certs: test certificates and signed documents in $out"
