"""The ground side's own MQTT broker: amqtt in the page's process, with Mosquitto's password
file and ACL rules (docs/mqtt.md, "The embedded broker")."""
