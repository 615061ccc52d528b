// Loads our message types the way lcm-spy does (lcm.spy.LCMTypeDatabase scans the class path)
// and checks each one by the fingerprint the C++ side computed, then decodes a message the C++
// side encoded (what lcm-spy does with every message). Arguments: name=fingerprint=file ...
// Prints "OK name" or "MISSING name" / "WRONG name got <class>" per argument.
public class CheckTypes {
  public static void main(String[] args) throws Exception {
    lcm.spy.LCMTypeDatabase db = new lcm.spy.LCMTypeDatabase();
    int bad = 0;
    for (String arg : args) {
      String[] kv = arg.split("=");
      long fingerprint = Long.parseLong(kv[1]);
      Class<?> cls = db.getClassByFingerprint(fingerprint);
      if (cls == null) {
        System.out.println("MISSING " + kv[0]);
        bad++;
      } else if (!cls.getName().equals("slamaware." + kv[0])) {
        System.out.println("WRONG " + kv[0] + " got " + cls.getName());
        bad++;
      } else {
        // The static fingerprint field must match too, and a C++-encoded message must decode.
        long field = cls.getField("LCM_FINGERPRINT").getLong(null);
        byte[] bytes = java.nio.file.Files.readAllBytes(java.nio.file.Paths.get(kv[2]));
        cls.getConstructor(byte[].class).newInstance((Object) bytes);
        System.out.println((field == fingerprint ? "OK " : "WRONG_FIELD ") + kv[0]);
        if (field != fingerprint) bad++;
      }
    }
    System.exit(bad == 0 ? 0 : 1);
  }
}
