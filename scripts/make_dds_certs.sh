#!/usr/bin/env bash
# Generates TEST certificates and signed DDS Security documents (never for deployment):
#   scripts/make_dds_certs.sh OUT_DIR [DOMAIN_ID] [TOPIC_PREFIX]
# OUT_DIR gets, all made with openssl:
#   ca.pem/ca_key.pem          the test CA (identity CA and permissions CA at once)
#   drone.pem/drone_key.pem    may publish and subscribe <prefix>/* (the perception drone)
#   rsu.pem/rsu_key.pem        may subscribe <prefix>/* (a roadside unit)
#   guest.pem/guest_key.pem    authenticated, but may only use guest/* (no perception topic)
#   governance.xml/.p7s        authentication required, discovery/liveliness/metadata/data
#                              encrypted, read and write access control on every topic
#   permissions.xml/.p7s       the three grants above, in DOMAIN_ID (default 0), any partition
# Running it twice into two folders gives two unrelated CAs (a participant of one cannot
# authenticate with the other), which the security test uses.
set -euo pipefail
out="${1:?usage: make_dds_certs.sh OUT_DIR [DOMAIN_ID] [TOPIC_PREFIX]}"
domain="${2:-0}"
prefix="${3:-vp}"
command -v openssl >/dev/null || { echo "make_dds_certs: openssl not found" >&2; exit 1; }
mkdir -p "$out"
cd "$out"
subj="/C=US/O=vehicle_perception test"
openssl req -x509 -newkey rsa:2048 -nodes -keyout ca_key.pem -out ca.pem -days 3650 \
  -subj "$subj/CN=VP Test CA $RANDOM$RANDOM" 2>/dev/null
for who in drone rsu guest; do
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
# grant NAME PUBLISH_TOPIC SUBSCRIBE_TOPIC (an empty PUBLISH_TOPIC grants no publication)
grant() {
  local who="$1" pub="$2" sub="$3" subject
  subject=$(openssl x509 -in "$who.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')
  echo "  <grant name=\"${who}_grant\"><subject_name>$subject</subject_name>"
  echo "    <validity><not_before>2020-01-01T00:00:00</not_before><not_after>2035-01-01T00:00:00</not_after></validity>"
  echo "    <allow_rule><domains><id>$domain</id></domains>"
  if [ -n "$pub" ]; then
    echo "      <publish><topics><topic>$pub</topic></topics><partitions><partition>*</partition></partitions></publish>"
  fi
  echo "      <subscribe><topics><topic>$sub</topic></topics><partitions><partition>*</partition></partitions></subscribe>"
  echo "    </allow_rule><default>DENY</default></grant>"
}
{
  echo '<?xml version="1.0" encoding="UTF-8"?>'
  echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd"><permissions>'
  grant drone "$prefix/*" "$prefix/*"
  grant rsu "" "$prefix/*"
  grant guest "guest/*" "guest/*"
  echo '</permissions></dds>'
} > permissions.xml
for doc in governance permissions; do
  openssl smime -sign -in "$doc.xml" -text -out "$doc.p7s" -signer ca.pem -inkey ca_key.pem
done
echo "make_dds_certs: test certificates and signed documents in $out"
